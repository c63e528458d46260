// A PNG whose header lies about its size: see lying_png.hpp.
#include "lying_png.hpp"

#include <cstdint>

namespace texwarp::testing {
namespace {

std::string be32(std::uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8), static_cast<char>(v)};
}

std::uint32_t crc32(const std::string& bytes) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (const unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

std::string png_chunk(const std::string& type, const std::string& data) {
  return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(crc32(type + data));
}

}  // namespace

std::string lying_png(int width, int height) {
  const std::string ihdr = be32(static_cast<std::uint32_t>(width)) + be32(static_cast<std::uint32_t>(height)) +
                           std::string("\x08\x06\x00\x00\x00", 5);
  std::string idat = "\x78\x01";  // zlib header; then a non-final stored block: LEN = 1000, NLEN = ~LEN
  idat += std::string("\x00\xe8\x03\x17\xfc", 5);
  idat += std::string(1000, '\0');
  return "\x89PNG\r\n\x1a\n" + png_chunk("IHDR", ihdr) + png_chunk("IDAT", idat) + png_chunk("IEND", "");
}

}  // namespace texwarp::testing
