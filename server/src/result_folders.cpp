// Jobs' result folders: see result_folders.hpp.
#include "texwarp/server/result_folders.hpp"

namespace texwarp::server {
namespace {

constexpr const char* kTemporaryPrefix = ".tmp-";

}  // namespace

ResultFolders::ResultFolders(const std::filesystem::path& data_dir) : root_(data_dir / "results") {
  std::filesystem::create_directories(root_);
}

std::filesystem::path ResultFolders::temporary(const std::string& job_id, int attempt) const {
  return root_ / (kTemporaryPrefix + job_id + "-" + std::to_string(attempt));
}

bool ResultFolders::is_temporary(const std::string& name) { return name.rfind(kTemporaryPrefix, 0) == 0; }

}  // namespace texwarp::server
