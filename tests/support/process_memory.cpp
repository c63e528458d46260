// /proc/PID/status memory fields: see process_memory.hpp.
#include "process_memory.hpp"

#include <fstream>

namespace texwarp::testing {

long process_memory_kib(pid_t pid, const std::string& field) {
  std::ifstream in(pid == 0 ? std::string("/proc/self/status") : "/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  }
  return -1;
}

}  // namespace texwarp::testing
