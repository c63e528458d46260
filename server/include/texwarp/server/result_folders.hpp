// ResultFolders: where jobs' result files live in the data folder. A run writes results/.tmp-<job>-<attempt>/,
// publishes it by renaming it to results/<job>/, and only published folders are served.
#pragma once

#include <filesystem>
#include <string>

namespace texwarp::server {

class ResultFolders {
 public:
  explicit ResultFolders(const std::filesystem::path& data_dir);  // creates results/

  const std::filesystem::path& root() const { return root_; }
  std::filesystem::path published(const std::string& job_id) const { return root_ / job_id; }
  std::filesystem::path temporary(const std::string& job_id, int attempt) const;
  // A folder name under root() that a run writes before publishing.
  static bool is_temporary(const std::string& name);

 private:
  std::filesystem::path root_;
};

}  // namespace texwarp::server
