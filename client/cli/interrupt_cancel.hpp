// InterruptCancel: SIGINT and SIGTERM (Ctrl-C, a farm scheduler's preemption) as a cancellation of the command's
// work. While one is alive, either signal sets the flag that its RunControls read: the work stops at its next check,
// throws CanceledError and unwinds, removing whatever it staged, so that no output is left half-written. A second
// signal ends the process at once (a phase that does not check: planning, a kernel compile, encoding). The previous
// dispositions come back when it ends. One at a time.
#pragma once

#include <atomic>

namespace texwarp::cli {

class InterruptCancel {
 public:
  using Handler = void (*)(int);

  InterruptCancel();
  ~InterruptCancel();
  InterruptCancel(const InterruptCancel&) = delete;
  InterruptCancel& operator=(const InterruptCancel&) = delete;

  // For RunControl::cancel.
  const std::atomic<bool>* flag() const { return flag_; }

 private:
  const std::atomic<bool>* flag_;
  Handler previous_int_ = nullptr;
  Handler previous_term_ = nullptr;
};

}  // namespace texwarp::cli
