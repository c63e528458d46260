// Content-addressed blob files: see blob_store.hpp.
#include "texwarp/server/blob_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <random>
#include <system_error>

#include "texwarp/core/atomic_file.hpp"
#include "texwarp/runner/fsync_path.hpp"
#include "texwarp/server/sha256.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

constexpr auto kSharedTemporaryAge =
    std::chrono::hours(1);  // a shared folder's temporary older than this is a leftover

std::string hex_of(const std::string& id) { return id.substr(7); }  // after "sha256:"

// Creates the blob's fan-out folder durably (its entry in blobs/ synced) when it is new.
void ensure_folder(const fs::path& folder) {
  if (fs::create_directories(folder)) runner::fsync_path(folder.parent_path());
}

// Writes `bytes` to a new file; std::system_error with the errno (ENOSPC on a full disk) on failure, the file
// removed.
void write_new_file(const fs::path& file, std::string_view bytes) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) throw std::system_error(errno, std::generic_category(), "cannot create " + file.string());
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : EIO;
      ::close(fd);
      std::error_code ec;
      fs::remove(file, ec);
      throw std::system_error(error, std::generic_category(), "cannot write " + file.string());
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) {
    const int error = errno;
    std::error_code ec;
    fs::remove(file, ec);
    throw std::system_error(error, std::generic_category(), "cannot write " + file.string());
  }
}

// A temporary file that an earlier version or a crashed process left beside a blob: ".<name>.tmp-<pid>-<n>".
bool is_stray_temporary(const fs::path& file) {
  const std::string name = file.filename().string();
  return name.size() > 1 && name[0] == '.' && name.find(".tmp-") != std::string::npos;
}

}  // namespace

BlobStore::BlobStore(const fs::path& root, Sharing sharing) : blobs_(root / "blobs"), tmp_(root / "tmp") {
  std::random_device random;
  const std::uint64_t token = (static_cast<std::uint64_t>(random()) << 32) ^ random();
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(token));
  temp_prefix_ = "upload-" + std::to_string(::getpid()) + "-" + hex + "-";
  fs::create_directories(blobs_);
  fs::create_directories(tmp_);
  temporaries_removed_ = remove_temporaries(sharing);
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
  const fs::path temp = temp_path();
  write_new_file(temp, bytes);
  publish_file(temp.string(), target.string());
  info.created = true;
  return info;
}

fs::path BlobStore::temp_path() { return tmp_ / (temp_prefix_ + std::to_string(counter_.fetch_add(1))); }

std::size_t BlobStore::remove_temporaries(Sharing sharing) {
  const auto cutoff = fs::file_time_type::clock::now() - kSharedTemporaryAge;
  std::error_code ec;
  // Shared: a temporary is another node's work in progress unless nobody touched it for a long time.
  const auto leftover = [&](const fs::path& p) {
    if (sharing == Sharing::kExclusive) return true;
    std::error_code tec;
    const auto t = fs::last_write_time(p, tec);
    return !tec && t < cutoff;
  };
  std::size_t removed = 0;
  for (const auto& entry : fs::directory_iterator(tmp_, ec)) {
    if (leftover(entry.path())) removed += fs::remove_all(entry.path(), ec) > 0 ? 1 : 0;
  }
  for (const auto& folder : fs::directory_iterator(blobs_, ec)) {
    if (!folder.is_directory(ec)) continue;
    for (const auto& entry : fs::directory_iterator(folder.path(), ec)) {
      if (is_stray_temporary(entry.path()) && leftover(entry.path())) {
        removed += fs::remove_all(entry.path(), ec) > 0 ? 1 : 0;
      }
    }
  }
  return removed;
}

// Not const although it changes no member: it adds a blob to the store (on disk).
proto::BlobInfo BlobStore::adopt(const fs::path& temp_file) {  // NOLINT(readability-make-member-function-const)
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
