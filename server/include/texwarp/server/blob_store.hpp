// BlobStore: uploaded files, content-addressed by SHA-256 ("sha256:<hex>") under <data>/blobs/<2 hex>/<hex>, written
// atomically (temporary file, fsync, rename) so that a blob that exists is whole. Identical uploads are kept once.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "texwarp/proto/blob_info.hpp"

namespace texwarp::server {

class BlobStore {
 public:
  // kExclusive: this process alone uses the folder (it holds the data folder's lock). kShared: nodes of a farm
  // share it, so another node's upload in progress must not be taken for a leftover.
  enum class Sharing { kExclusive, kShared };

  // Creates <root>/blobs and <root>/tmp; removes temporary files a previous process left behind (uploads being
  // received in tmp/, half-written blobs beside their targets): all of them when exclusive, when shared only those
  // untouched for an hour.
  explicit BlobStore(const std::filesystem::path& root, Sharing sharing = Sharing::kExclusive);
  std::size_t temporaries_removed() const { return temporaries_removed_; }  // by the constructor

  bool contains(const std::string& id) const;
  std::optional<std::uint64_t> size(const std::string& id) const;
  std::filesystem::path path_of(const std::string& id) const;  // where the blob is (or would be); id must be valid

  // Stores bytes (a no-op but for the answer when the same bytes are stored already). std::system_error with
  // the errno when the file cannot be written (ENOSPC: the disk is full).
  proto::BlobInfo put(std::string_view bytes);

  // A fresh path in the store's temporary folder, for an upload being received.
  std::filesystem::path temp_path();
  // Takes a fully received upload from temp_path(): hashes it, fsyncs it and renames it into place (or removes
  // it when the blob exists already).
  proto::BlobInfo adopt(const std::filesystem::path& temp_file);

 private:
  std::size_t remove_temporaries(Sharing sharing);

  std::filesystem::path blobs_;
  std::filesystem::path tmp_;
  std::string temp_prefix_;  // "upload-<pid>-<random>-": unique among the nodes sharing the folder
  std::atomic<std::uint64_t> counter_{0};
  std::size_t temporaries_removed_ = 0;
};

}  // namespace texwarp::server
