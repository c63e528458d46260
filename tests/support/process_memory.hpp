// Memory of a running process as the kernel reports it (/proc/PID/status), for tests that bound what a request,
// a job or a decode may cost.
#pragma once

#include <sys/types.h>

#include <string>

namespace texwarp::testing {

// A "Vm…" field of /proc/PID/status in KiB ("VmRSS": resident now, "VmHWM": peak resident); pid 0 is this
// process. -1 when the process or the field is not there.
long process_memory_kib(pid_t pid, const std::string& field);

// Whether resident memory measures what a process's code holds: not under AddressSanitizer, whose shadow (an eighth
// of every allocation, touched or not) and quarantine of freed blocks come on top, nor under ThreadSanitizer, whose
// shadow is several times the memory it watches (a JSON nesting bomb's refusal: VmHWM +331 MiB against 100).
// Tests bound memory only where it does (scripts/sanitize.sh).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kResidentMemoryIsMeasured = false;
#else
inline constexpr bool kResidentMemoryIsMeasured = true;
#endif

}  // namespace texwarp::testing
