// A shell command run by a test, its exit status and standard output captured (header only, for every test binary).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace texwarp::testing {

struct ShellOutput {
  int status = -1;     // the exit status; −1 when it did not exit normally (or could not start)
  std::string output;  // standard output (redirect 2>&1 in `command` for standard error too)
};

inline ShellOutput run_shell(const std::string& command) {
  ShellOutput r;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) r.output.append(buffer, n);
  const int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace texwarp::testing
