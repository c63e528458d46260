// Content-addressed blob files: see blob_store.hpp.
#include "texwarp/server/blob_store.hpp"

#include <unistd.h>

#include <system_error>

#include "texwarp/core/atomic_file.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/runner/fsync_path.hpp"
#include "texwarp/server/sha256.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

std::string hex_of(const std::string& id) { return id.substr(7); }  // after "sha256:"

// Creates the blob's fan-out folder durably (its entry in blobs/ synced) when it is new.
void ensure_folder(const fs::path& folder) {
  if (fs::create_directories(folder)) runner::fsync_path(folder.parent_path());
}

}  // namespace

BlobStore::BlobStore(fs::path root) : blobs_(root / "blobs"), tmp_(root / "tmp") {
  fs::create_directories(blobs_);
  fs::create_directories(tmp_);
  for (const auto& entry : fs::directory_iterator(tmp_)) {
    std::error_code ec;
    fs::remove_all(entry.path(), ec);
  }
}

fs::path BlobStore::path_of(const std::string& id) const {
  const std::string hex = hex_of(id);
  return blobs_ / hex.substr(0, 2) / hex;
}

bool BlobStore::contains(const std::string& id) const {
  std::error_code ec;
  return fs::is_regular_file(path_of(id), ec);
}

std::optional<std::uint64_t> BlobStore::size(const std::string& id) const {
  std::error_code ec;
  const auto n = fs::file_size(path_of(id), ec);
  if (ec) return std::nullopt;
  return static_cast<std::uint64_t>(n);
}

proto::BlobInfo BlobStore::put(std::string_view bytes) {
  proto::BlobInfo info;
  info.id = "sha256:" + sha256_hex(bytes);
  info.bytes = bytes.size();
  const fs::path target = path_of(info.id);
  if (contains(info.id)) return info;
  ensure_folder(target.parent_path());
  write_text_file_atomically(target.string(), bytes);
  info.created = true;
  return info;
}

fs::path BlobStore::temp_path() {
  return tmp_ / ("upload-" + std::to_string(::getpid()) + "-" + std::to_string(counter_.fetch_add(1)));
}

proto::BlobInfo BlobStore::adopt(const fs::path& temp_file) {
  proto::BlobInfo info;
  std::uint64_t bytes = 0;
  info.id = "sha256:" + sha256_file_hex(temp_file, &bytes);
  info.bytes = bytes;
  const fs::path target = path_of(info.id);
  if (contains(info.id)) {
    std::error_code ec;
    fs::remove(temp_file, ec);
    return info;
  }
  ensure_folder(target.parent_path());
  publish_file(temp_file.string(), target.string());
  info.created = true;
  return info;
}

}  // namespace texwarp::server
