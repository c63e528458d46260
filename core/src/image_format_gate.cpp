// Format sniffing and the declared-size checks of OpenEXR headers and PNG chunks: see image_format_gate.hpp.
#include "texwarp/core/image_format_gate.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string_view>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp {
namespace {

constexpr std::string_view kExrMagic("\x76\x2f\x31\x01", 4);
constexpr std::string_view kPngMagic("\x89PNG\r\n\x1a\n", 8);

// OpenEXR 3.1's attribute types of a fixed size (ImfStandardAttributes and friends), in bytes.
const std::map<std::string, long long, std::less<>> kFixedAttributeSizes = {
    {"box2i", 16},      {"box2f", 16},   {"chromaticities", 32},
    {"compression", 1}, {"double", 8},   {"envmap", 1},
    {"float", 4},       {"int", 4},      {"keycode", 28},
    {"lineOrder", 1},   {"m33f", 36},    {"m33d", 72},
    {"m44f", 64},       {"m44d", 128},   {"rational", 8},
    {"tiledesc", 9},    {"timecode", 8}, {"v2i", 8},
    {"v2f", 8},         {"v2d", 16},     {"v3i", 12},
    {"v3f", 12},        {"v3d", 24},     {"deepImageState", 1}};

struct Magic {
  std::string_view bytes;
  std::size_t offset;
  const char* format;
};

constexpr Magic kMagics[] = {
    {kPngMagic, 0, "png"},
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
    if (head.size() >= m.offset + m.bytes.size() &&
        std::string_view(head).substr(m.offset, m.bytes.size()) == m.bytes) {
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
  const bool multipart = (static_cast<unsigned char>(head[5]) & 0x10) != 0;   // version flags, bit 12
  const bool long_names = (static_cast<unsigned char>(head[5]) & 0x04) != 0;  // bit 10
  const auto cut_short = [&] {
    throw InputError(InputLocation::file(path), "not a valid OpenEXR file: its header is cut short");
  };
  // Names end with a NUL within 31 characters (255 with long names). OpenEXR reads a longer one in its own way
  // (its end unmarked), which would make it take other bytes for the next sizes than this check did: refused.
  const std::size_t max_name = long_names ? 255 : 31;
  const auto read_name = [&](std::string& out) {
    out.clear();
    for (char c;;) {
      if (!in.get(c)) cut_short();
      if (c == '\0') return;
      if (out.size() == max_name) {
        throw InputError(InputLocation::file(path), "not a valid OpenEXR file: a header name is longer than " +
                                                        std::to_string(max_name) + " characters");
      }
      out += c;
    }
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
      const long long size =
          static_cast<std::int32_t>(static_cast<std::uint32_t>(s[0]) | static_cast<std::uint32_t>(s[1]) << 8 |
                                    static_cast<std::uint32_t>(s[2]) << 16 | static_cast<std::uint32_t>(s[3]) << 24);
      const auto too_large = [&](long long bytes) {
        return bytes < 0 || bytes > file_size - static_cast<long long>(in.tellg());
      };
      const auto refuse = [&](const std::string& why) {
        throw InputError(InputLocation::file(path),
                         "not a valid OpenEXR file: header attribute \"" + proto::utf8_prefix(name, 64) + "\" " + why);
      };
      if (too_large(size)) refuse("declares " + std::to_string(size) + " bytes, more than the file holds");
      // OpenEXR reads attributes of its own types by their type, not by the size they declare: a size that does not
      // fit its type would make it read other bytes as the next sizes than this check did. A valid file never has one.
      const long long start = static_cast<long long>(in.tellg());
      if (const auto fixed = kFixedAttributeSizes.find(type); fixed != kFixedAttributeSizes.end()) {
        if (size != fixed->second)
          refuse("of type " + type + " declares " + std::to_string(size) + " bytes, not " +
                 std::to_string(fixed->second));
      } else if (type == "chlist") {  // read up to its terminating empty name
        std::string channel;
        for (read_name(channel); !channel.empty(); read_name(channel)) in.seekg(16, std::ios::cur);
        if (static_cast<long long>(in.tellg()) - start != size)
          refuse("(a channel list) does not fill the bytes it declares");
      } else if (type == "preview") {  // pixels allocated from width × height
        unsigned char wh[8];
        if (!in.read(reinterpret_cast<char*>(wh), 8)) cut_short();
        const auto u32 = [&](int k) {
          return static_cast<long long>(static_cast<std::uint32_t>(wh[k]) | static_cast<std::uint32_t>(wh[k + 1]) << 8 |
                                        static_cast<std::uint32_t>(wh[k + 2]) << 16 |
                                        static_cast<std::uint32_t>(wh[k + 3]) << 24);
        };
        // 8 + 4 × width × height == size, without the product (up to 2^66) overflowing.
        const long long width = u32(0);
        const long long height = u32(4);
        const long long pixels = (size - 8) / 4;
        const bool fills = size >= 8 && (size - 8) % 4 == 0 &&
                           (width == 0 || height == 0 ? pixels == 0 : pixels % width == 0 && pixels / width == height);
        if (!fills) refuse("(a preview) does not fill the bytes it declares");
      }
      in.seekg(start + size, std::ios::beg);
      read_name(name);
    }
  } while (multipart);
}

void check_png_chunk_sizes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  if (!in.read(head, 8) || std::string_view(head, 8) != kPngMagic) return;
  std::error_code ec;
  const auto file_size = static_cast<long long>(std::filesystem::file_size(path, ec));
  if (ec) return;  // the decoder says what is wrong with a file that cannot be sized
  const auto refuse = [&](const std::string& why) {
    throw InputError(InputLocation::file(path), "is truncated or corrupt: " + why);
  };
  for (long long at = 8; at < file_size;) {
    unsigned char h[8];
    if (!in.read(reinterpret_cast<char*>(h), 8))
      refuse("the chunk header at byte " + std::to_string(at) + " is cut short");
    const long long length =
        static_cast<long long>(static_cast<std::uint32_t>(h[0]) << 24 | static_cast<std::uint32_t>(h[1]) << 16 |
                               static_cast<std::uint32_t>(h[2]) << 8 | static_cast<std::uint32_t>(h[3]));
    const std::string type(reinterpret_cast<const char*>(h) + 4, 4);
    for (const char c : type) {
      if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z')))
        refuse("the chunk at byte " + std::to_string(at) + " has a type that is not four letters");
    }
    const long long left = file_size - at - 8 - 4;  // after the chunk's header, less its CRC
    if (length > left) {
      refuse("the " + type + " chunk at byte " + std::to_string(at) + " declares " + std::to_string(length) +
             " bytes, more than the " + std::to_string(std::max(0LL, left)) + " the file holds after it");
    }
    if (type == "IEND") return;
    at += 12 + length;
    in.seekg(at, std::ios::beg);
  }
}

std::optional<std::pair<long long, long long>> webp_canvas_size(const std::string& path) {
  const std::string h = first_bytes(path, 30);
  if (h.size() < 30 || h.compare(0, 4, "RIFF") != 0 || h.compare(8, 4, "WEBP") != 0) return std::nullopt;
  const auto byte = [&](std::size_t k) { return static_cast<long long>(static_cast<unsigned char>(h[k])); };
  const std::string_view chunk = std::string_view(h).substr(12, 4);
  if (chunk == "VP8X") {  // canvas width − 1 and height − 1, 24 bits little-endian each
    return std::pair{1 + (byte(24) | byte(25) << 8 | byte(26) << 16), 1 + (byte(27) | byte(28) << 8 | byte(29) << 16)};
  }
  if (chunk == "VP8L" && byte(20) == 0x2f) {  // 14 bits width − 1, 14 bits height − 1
    const long long bits = byte(21) | byte(22) << 8 | byte(23) << 16 | byte(24) << 24;
    return std::pair{1 + (bits & 0x3fff), 1 + ((bits >> 14) & 0x3fff)};
  }
  if (chunk == "VP8 " && byte(23) == 0x9d && byte(24) == 0x01 && byte(25) == 0x2a) {  // key frame: 14-bit sizes
    return std::pair{(byte(26) | byte(27) << 8) & 0x3fff, (byte(28) | byte(29) << 8) & 0x3fff};
  }
  return std::nullopt;
}

}  // namespace texwarp
