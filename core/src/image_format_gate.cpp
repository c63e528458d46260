// Format sniffing and the OpenEXR header-size check: see image_format_gate.hpp.
#include "texwarp/core/image_format_gate.hpp"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp {
namespace {

constexpr std::string_view kExrMagic("\x76\x2f\x31\x01", 4);

struct Magic {
  std::string_view bytes;
  std::size_t offset;
  const char* format;
};

constexpr Magic kMagics[] = {
    {std::string_view("\x89PNG\r\n\x1a\n", 8), 0, "png"},
    {std::string_view("\xff\xd8\xff", 3), 0, "jpeg"},
    {std::string_view("II*\0", 4), 0, "tiff"},
    {std::string_view("MM\0*", 4), 0, "tiff"},
    {std::string_view("II+\0", 4), 0, "tiff"},  // BigTIFF
    {std::string_view("MM\0+", 4), 0, "tiff"},
    {kExrMagic, 0, "openexr"},
    {std::string_view("BM", 2), 0, "bmp"},
    {std::string_view("WEBP", 4), 8, "webp"},  // after "RIFF" and a size
    {std::string_view("#?RADIANCE", 10), 0, "hdr"},
    {std::string_view("#?RGBE", 6), 0, "hdr"},
};

std::string first_bytes(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head;
}

}  // namespace

std::string sniff_image_format(const std::string& path) {
  const std::string head = first_bytes(path, 16);
  for (const Magic& m : kMagics) {
    if (head.size() >= m.offset + m.bytes.size() && std::string_view(head).substr(m.offset, m.bytes.size()) == m.bytes) {
      if (m.offset == 8 && head.compare(0, 4, "RIFF") != 0) continue;
      return m.format;
    }
  }
  return {};
}

void check_exr_header_sizes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  if (!in.read(head, 8) || std::string_view(head, 4) != kExrMagic) return;
  std::error_code ec;
  const auto file_size = static_cast<long long>(std::filesystem::file_size(path, ec));
  const bool multipart = (static_cast<unsigned char>(head[5]) & 0x10) != 0;  // version flags, bit 12
  const auto cut_short = [&] { throw InputError(path, "not a valid OpenEXR file: its header is cut short"); };
  const auto read_name = [&](std::string& out) {  // NUL-terminated, at most 255 bytes
    out.clear();
    for (char c; in.get(c);) {
      if (c == '\0') return;
      if (out.size() == 255) cut_short();
      out += c;
    }
    cut_short();
  };
  std::string name;
  std::string type;
  do {
    read_name(name);
    if (name.empty()) break;  // the end of a multi-part file's list of headers
    while (!name.empty()) {
      read_name(type);
      unsigned char s[4];
      if (!in.read(reinterpret_cast<char*>(s), 4)) cut_short();
      const long long size = static_cast<std::int32_t>(static_cast<std::uint32_t>(s[0]) | static_cast<std::uint32_t>(s[1]) << 8 |
                                                       static_cast<std::uint32_t>(s[2]) << 16 |
                                                       static_cast<std::uint32_t>(s[3]) << 24);
      if (size < 0 || size > file_size - static_cast<long long>(in.tellg())) {
        throw InputError(path, "not a valid OpenEXR file: header attribute \"" + proto::utf8_prefix(name, 64) +
                                   "\" declares " + std::to_string(size) + " bytes, more than the file holds");
      }
      in.seekg(size, std::ios::cur);
      read_name(name);
    }
  } while (multipart);
}

}  // namespace texwarp
