// The on-disk cache of built OpenCL programs: see program_cache.hpp.
#include "program_cache.hpp"

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string_view>

#include "opencl_device.hpp"
#include "texwarp/core/atomic_file.hpp"

namespace texwarp::kernels_detail {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kMagic = "texwarp-program-cache 1\n";

// The key as stored in the file: its four parts separated by NUL bytes.
std::string flat(const ProgramKey& key) {
  return key.device + '\0' + key.driver + '\0' + key.options + '\0' + key.source;
}

std::uint64_t fnv1a(std::string_view text) {
  std::uint64_t h = 14695981039346656037ULL;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

void put_size(std::string& out, std::uint64_t n) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((n >> (8 * i)) & 0xff));
}

// Reads a little-endian 64-bit size at `at` (advanced); false past the end.
bool get_size(std::string_view in, std::size_t& at, std::uint64_t& n) {
  if (in.size() - at < 8) return false;
  n = 0;
  for (int i = 0; i < 8; ++i) n |= static_cast<std::uint64_t>(static_cast<unsigned char>(in[at + i])) << (8 * i);
  at += 8;
  return true;
}

}  // namespace

fs::path program_cache_file(const ProgramKey& key) {
  const fs::path dir = cache_dir();
  if (dir.empty()) return {};
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.bin", static_cast<unsigned long long>(fnv1a(flat(key))));
  return dir / "programs" / name;
}

std::optional<std::vector<unsigned char>> load_program_binary(const ProgramKey& key) {
  const fs::path file = program_cache_file(key);
  if (file.empty()) return std::nullopt;
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string_view data = bytes;
  if (!data.starts_with(kMagic)) return std::nullopt;
  std::size_t at = kMagic.size();
  std::uint64_t key_size = 0;
  std::uint64_t binary_size = 0;
  const std::string wanted = flat(key);
  if (!get_size(data, at, key_size) || key_size != wanted.size() || data.size() - at < key_size) return std::nullopt;
  if (data.substr(at, key_size) != wanted) return std::nullopt;
  at += key_size;
  if (!get_size(data, at, binary_size) || binary_size == 0 || data.size() - at != binary_size) return std::nullopt;
  return std::vector<unsigned char>(data.begin() + static_cast<std::ptrdiff_t>(at), data.end());
}

void store_program_binary(const ProgramKey& key, const std::vector<unsigned char>& binary) {
  const fs::path file = program_cache_file(key);
  if (file.empty() || binary.empty()) return;
  std::error_code ec;
  fs::create_directories(file.parent_path(), ec);
  if (ec) return;
  std::string out(kMagic);
  const std::string k = flat(key);
  put_size(out, k.size());
  out += k;
  put_size(out, binary.size());
  out.append(reinterpret_cast<const char*>(binary.data()), binary.size());
  const std::string temp = temporary_path_for(file.string());
  try {
    {
      std::ofstream o(temp, std::ios::binary | std::ios::trunc);
      o.write(out.data(), static_cast<std::streamsize>(out.size()));
      if (!o.flush()) throw std::runtime_error("short write");
    }
    publish_file(temp, file.string());
  } catch (const std::exception&) {
    fs::remove(temp, ec);  // a cache that cannot be written is only slower
  }
}

}  // namespace texwarp::kernels_detail
