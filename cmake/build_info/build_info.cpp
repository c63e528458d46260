// The version texwarp's binaries print (build_info.hpp); the commit is in the generated build_commit.cpp.
#include "texwarp/build_info.hpp"

namespace texwarp {

const char* build_version() { return TEXWARP_VERSION; }

std::string version_line(const std::string& program) {
  return program + " " + build_version() + " (commit " + build_commit() + ")";
}

}  // namespace texwarp
