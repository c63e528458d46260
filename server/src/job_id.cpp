// Job ids: see job_id.hpp.
#include "texwarp/server/job_id.hpp"

#include <algorithm>
#include <cstdint>
#include <random>

#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::server {

std::string new_job_id() {
  thread_local std::random_device device;
  thread_local std::mt19937_64 rng((static_cast<std::uint64_t>(device()) << 32) ^ device());
  static constexpr char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz234567";
  const std::uint64_t hi = rng() ^ (static_cast<std::uint64_t>(device()) << 32);
  const std::uint64_t lo = rng() ^ device();
  std::string id = "job_";
  for (int i = 0; i < 26; ++i) {
    const int bit = i * 5;
    std::uint64_t v = 0;
    for (int b = 0; b < 5; ++b) {
      const int k = bit + b;
      const std::uint64_t word = k < 64 ? hi : lo;
      v = (v << 1) | ((word >> (63 - (k % 64))) & 1U);
    }
    id.push_back(kAlphabet[v]);
  }
  return id;
}

bool is_job_id(const std::string& id) {
  if (id.size() != 30 || id.rfind("job_", 0) != 0) return false;
  return std::all_of(id.begin() + 4, id.end(), [](char c) { return (c >= 'a' && c <= 'z') || (c >= '2' && c <= '7'); });
}

ServiceError job_not_found(const std::string& id) {
  return ServiceError(ErrorKind::kNotFound, "there is no job \"" + proto::utf8_prefix(id, 64) + "\" on this server");
}

}  // namespace texwarp::server
