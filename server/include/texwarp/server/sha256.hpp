// SHA-256 (OpenSSL's EVP digest) for content-addressed blobs, idempotency fingerprints and result files:
// incremental, and one-shot over bytes or a file; lowercase hex out.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace texwarp::server {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void update(std::string_view bytes);
  std::string hex_digest();  // finishes the digest; the object is done afterwards

 private:
  struct State;
  std::unique_ptr<State> state_;
};

std::string sha256_hex(std::string_view bytes);
// std::runtime_error when the file cannot be read.
std::string sha256_file_hex(const std::filesystem::path& path, std::uint64_t* bytes = nullptr);

}  // namespace texwarp::server
