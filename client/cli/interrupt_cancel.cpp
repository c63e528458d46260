// SIGINT and SIGTERM as a cancellation flag: see interrupt_cancel.hpp.
#include "interrupt_cancel.hpp"

#include <csignal>

namespace texwarp::cli {
namespace {

std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler stores to it");

// The first signal asks the work to stop; a second (the work is in a phase that does not check, or the user
// insists) takes the signal's default action at once. signal() and raise() are async-signal-safe.
extern "C" void on_interrupt(int signal) {
  if (g_interrupted.exchange(true)) {
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }
}

// Installs the handler, even where the process was started with the signal ignored (a background job of a
// non-interactive shell starts so for SIGINT, and a farm's script cancels such a job with it), and returns the
// disposition to restore.
InterruptCancel::Handler install(int signal) {
  const InterruptCancel::Handler previous = std::signal(signal, on_interrupt);
  return previous == SIG_ERR ? SIG_DFL : previous;
}

}  // namespace

InterruptCancel::InterruptCancel() : flag_(&g_interrupted) {
  g_interrupted.store(false);
  previous_int_ = install(SIGINT);
  previous_term_ = install(SIGTERM);
}

InterruptCancel::~InterruptCancel() {
  std::signal(SIGINT, previous_int_);
  std::signal(SIGTERM, previous_term_);
}

}  // namespace texwarp::cli
