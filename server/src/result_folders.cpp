// Jobs' result folders: see result_folders.hpp.
#include "texwarp/server/result_folders.hpp"

#include <charconv>

#include "texwarp/server/job_id.hpp"

namespace texwarp::server {
namespace {

constexpr std::string_view kTemporaryPrefix = ".tmp-";

std::optional<std::int64_t> parse_epoch(std::string_view text) {
  std::int64_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || v < 0) return std::nullopt;
  return v;
}

}  // namespace

ResultFolders::ResultFolders(const std::filesystem::path& data_dir) : root_(data_dir / "results") {
  std::filesystem::create_directories(root_);
}

std::filesystem::path ResultFolders::temporary(const std::string& job_id, std::int64_t epoch) const {
  return root_ / (std::string(kTemporaryPrefix) + job_id + "-" + std::to_string(epoch));
}

std::string ResultFolders::published_name(const std::string& job_id, std::int64_t epoch) {
  return job_id + "." + std::to_string(epoch);
}

ResultFolderName ResultFolders::parse(const std::string& name) {
  ResultFolderName out;
  if (name.rfind(kTemporaryPrefix, 0) == 0) {
    const std::string rest = name.substr(kTemporaryPrefix.size());
    const auto dash = rest.rfind('-');
    if (dash == std::string::npos) return out;
    const auto epoch = parse_epoch(std::string_view(rest).substr(dash + 1));
    if (!epoch || !is_job_id(rest.substr(0, dash))) return out;
    return {ResultFolderName::Kind::kTemporary, rest.substr(0, dash), *epoch};
  }
  if (is_job_id(name)) return {ResultFolderName::Kind::kLegacy, name, 0};
  const auto dot = name.rfind('.');
  if (dot == std::string::npos) return out;
  const auto epoch = parse_epoch(std::string_view(name).substr(dot + 1));
  if (!epoch || !is_job_id(name.substr(0, dot))) return out;
  return {ResultFolderName::Kind::kPublished, name.substr(0, dot), *epoch};
}

}  // namespace texwarp::server
