// RunControl helpers: see run_control.hpp.
#include "texwarp/core/run_control.hpp"

#include <thread>

namespace texwarp {

int RunControl::thread_count() const {
  if (threads > 0) return threads;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

}  // namespace texwarp
