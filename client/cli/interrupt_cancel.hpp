// InterruptCancel: SIGINT and SIGTERM (Ctrl-C, a farm scheduler's preemption) as a cancellation of the command's
// work. While one is alive, either signal sets the flag that its RunControls read: the work stops at its next check,
// throws CanceledError and unwinds, removing whatever it staged, so that no output is left half-written. The
// default actions come back when it ends. One at a time per process.
#pragma once

#include <atomic>

namespace texwarp::cli {

class InterruptCancel {
 public:
  InterruptCancel();
  ~InterruptCancel();
  InterruptCancel(const InterruptCancel&) = delete;
  InterruptCancel& operator=(const InterruptCancel&) = delete;

  // For RunControl::cancel.
  const std::atomic<bool>* flag() const { return flag_; }

 private:
  const std::atomic<bool>* flag_;
};

}  // namespace texwarp::cli
