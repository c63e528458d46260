// What the binaries were built from: texwarp's version (project() VERSION of the top-level CMakeLists.txt) and the
// git commit of the source tree at build time, for `texwarp --version` and `texwarpd --version`.
#pragma once

#include <string>

namespace texwarp {

const char* build_version();  // "0.1.0"
const char* build_commit();   // `git rev-parse --short HEAD` ("4de8b0c"), or "unknown" outside a git checkout

// "PROGRAM VERSION (commit COMMIT)", e.g. "texwarp 0.1.0 (commit 4de8b0c)".
std::string version_line(const std::string& program);

}  // namespace texwarp
