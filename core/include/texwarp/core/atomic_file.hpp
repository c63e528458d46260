// Atomic file publication: write to a temporary file beside the target, fsync it, rename it over the target
// and fsync the folder, so that a reader sees the old file or the whole new one, never a part.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace texwarp {

// A fresh hidden path in the target's folder that keeps the target's extension (file-format detection).
std::string temporary_path_for(const std::string& target);

// fsyncs `temporary`, renames it to `target`, fsyncs the folder. On failure removes `temporary` and throws
// std::runtime_error naming the target.
void publish_file(const std::string& temporary, const std::string& target);

// Files published together (the outputs of a texture set): each is written to its staging path first, and all are
// put in place by publish_all once every one is written; destroyed before that, it removes what was staged and the
// folders it made, so that a failure part way through leaves none of the set's files and no empty output folder.
class StagedFiles {
 public:
  StagedFiles() = default;
  StagedFiles(const StagedFiles&) = delete;
  StagedFiles& operator=(const StagedFiles&) = delete;
  ~StagedFiles();

  // A staging path for `target` (temporary_path_for: same folder, same extension), remembered.
  std::string stage(const std::string& target);
  // `folder` and its missing parents made (std::filesystem::create_directories); those made are remembered and
  // removed again, when empty, unless publish_all runs. Throws std::filesystem::filesystem_error.
  void make_folder(const std::string& folder);
  // publish_file for every staged file, in the order staged.
  void publish_all();

 private:
  std::vector<std::pair<std::string, std::string>> staged_;  // (staging path, target)
  std::vector<std::string> made_;                            // folders make_folder made, outermost first
};

}  // namespace texwarp
