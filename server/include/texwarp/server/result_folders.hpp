// ResultFolders: where jobs' result files live in the (possibly shared) data folder. A run under lease epoch E
// writes results/.tmp-<job>-<E>/, publishes it by renaming it to results/<job>.<E>/ (never over another folder),
// and the job's row then names that folder; only a folder a succeeded row names is served. Rows of the first
// schema name results/<job>/.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace texwarp::server {

// What a folder name under results/ says about itself.
struct ResultFolderName {
  enum class Kind { kTemporary, kPublished, kLegacy, kOther };
  Kind kind = Kind::kOther;
  std::string job_id;
  std::int64_t epoch = 0;  // kTemporary, kPublished
};

class ResultFolders {
 public:
  explicit ResultFolders(const std::filesystem::path& data_dir);  // creates results/

  const std::filesystem::path& root() const { return root_; }
  // The folder a row names (its result_folder).
  std::filesystem::path folder(const std::string& result_folder) const { return root_ / result_folder; }
  std::filesystem::path temporary(const std::string& job_id, std::int64_t epoch) const;
  // "<job>.<epoch>": a run's published folder, as its row names it.
  static std::string published_name(const std::string& job_id, std::int64_t epoch);
  static ResultFolderName parse(const std::string& name);

 private:
  std::filesystem::path root_;
};

}  // namespace texwarp::server
