// SIGINT and SIGTERM as a cancellation flag: see interrupt_cancel.hpp.
#include "interrupt_cancel.hpp"

#include <csignal>

namespace texwarp::cli {
namespace {

std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler stores to it");

extern "C" void on_interrupt(int) { g_interrupted.store(true); }

}  // namespace

InterruptCancel::InterruptCancel() : flag_(&g_interrupted) {
  g_interrupted.store(false);
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

InterruptCancel::~InterruptCancel() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

}  // namespace texwarp::cli
