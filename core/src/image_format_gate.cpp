// Format sniffing and the declared-size checks of OpenEXR headers and PNG chunks: see image_format_gate.hpp.
#include "texwarp/core/image_format_gate.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <string_view>
#include <vector>

#include <zlib.h>

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

// What an OpenEXR part's header declares that OpenEXR allocates from when it opens the part.
constexpr long long kNoDataWindow = -1;
struct ExrPartLayout {
  long long width = kNoDataWindow;  // of the data window
  long long height = kNoDataWindow;
  long long tile_width = 0;  // of the "tiles" attribute; 0 when there is none
  long long tile_height = 0;
  int tile_level_mode = 0;        // ONE_LEVEL, MIPMAP_LEVELS, RIPMAP_LEVELS
  long long bytes_per_pixel = 0;  // over the channel list
  bool subsampled = false;        // a channel with x or y sampling other than 1
  int channels = 0;
  int compression = -1;  // OpenEXR's code (ImfCompression.h)
  std::optional<long long> chunk_count;
  std::string type;  // "scanlineimage", "tiledimage", "deepscanline", "deeptile"
};

// Scan lines in one chunk of a scan-line part, by OpenEXR's compression code (none, RLE, ZIPS, ZIP, PIZ, PXR24,
// B44, B44A, DWAA, DWAB); 0 for a code OpenEXR does not know (it refuses the file itself).
long long exr_lines_per_chunk(int compression) {
  constexpr long long kLines[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
  return compression >= 0 && compression < static_cast<int>(std::size(kLines)) ? kLines[compression] : 0;
}

// OpenEXR allocates, when it opens a part, its table of chunk offsets (8 bytes a chunk) and buffers of a whole tile
// each. The table is in the file, so a valid file holds it; a tile larger than kMaxExrTileBytes is refused whatever
// the file (an 884-byte file declaring 14000×14000 tiles made OpenEXR allocate 1.2 GB: fuzz_image_header).
void check_exr_part_layout(const ExrPartLayout& layout, long long file_size, const std::string& path,
                           const std::string& part) {
  const auto refuse = [&](const std::string& why) { throw InputError(InputLocation::file(path), part + why); };
  const long long max_chunks = file_size / 8;
  if (layout.chunk_count && (*layout.chunk_count < 0 || *layout.chunk_count > max_chunks)) {
    refuse("not a valid OpenEXR file: it declares " + std::to_string(*layout.chunk_count) +
           " chunks, whose offsets (8 bytes each) are more than the file's " + std::to_string(file_size) + " bytes");
  }
  const bool tiled = layout.type == "tiledimage" || layout.type == "deeptile";
  if (tiled && layout.tile_width > 0 && layout.tile_height > 0) {
    const long long tile_pixels_allowed = kMaxExrTileBytes / std::max(layout.bytes_per_pixel, 1LL);
    if (layout.tile_width > tile_pixels_allowed || layout.tile_height > tile_pixels_allowed / layout.tile_width) {
      refuse("OpenEXR tiles of " + std::to_string(layout.tile_width) + "×" + std::to_string(layout.tile_height) +
             " pixels are larger than texwarp reads (at most " + std::to_string(kMaxExrTileBytes >> 20) +
             " MiB a tile); save the image with smaller tiles (e.g. oiiotool in.exr --tile 64 64 -o out.exr)");
    }
  }
  if (layout.width <= 0 || layout.height <= 0) return;  // OpenEXR refuses an empty or missing data window itself
  // The chunks of the full-resolution level alone (a tiled part's other levels add more), counted without overflow:
  // across × down > max_chunks ⇔ down > max_chunks / across (integer division).
  long long across = 1;
  long long down = 0;
  if (tiled) {
    if (layout.tile_width <= 0 || layout.tile_height <= 0) return;
    across = (layout.width + layout.tile_width - 1) / layout.tile_width;
    down = (layout.height + layout.tile_height - 1) / layout.tile_height;
  } else if (const long long lines = exr_lines_per_chunk(layout.compression); lines > 0) {
    down = (layout.height + lines - 1) / lines;
  }
  if (across > max_chunks || down > max_chunks / across) {
    refuse("not a valid OpenEXR file: its " + std::to_string(layout.width) + "×" + std::to_string(layout.height) +
           " data window takes " +
           (tiled ? std::to_string(across) + "×" + std::to_string(down) + " tiles"
                  : std::to_string(down) + " chunks of scan lines") +
           ", whose offsets (8 bytes each) are more than the file's " + std::to_string(file_size) + " bytes");
  }
}

// Bytes of a file at given offsets, read on demand a block at a time; nullopt past its end.
class FileBytes {
 public:
  explicit FileBytes(const std::string& path) : in_(path, std::ios::binary) {}
  // `n` (≤ 8) bytes at `at` as an unsigned integer, big- or little-endian.
  std::optional<std::uint64_t> uint(std::uint64_t at, int n, bool big_endian) {
    std::uint64_t v = 0;
    for (int k = 0; k < n; ++k) {
      const auto b = byte(at + static_cast<std::uint64_t>(k));
      if (!b) return std::nullopt;
      v |= static_cast<std::uint64_t>(*b) << (8 * (big_endian ? n - 1 - k : k));
    }
    return v;
  }

 private:
  static constexpr std::uint64_t kBlock = 1 << 16;
  std::optional<unsigned char> byte(std::uint64_t at) {
    if (at < block_at_ || at >= block_at_ + block_.size()) {
      if (at > static_cast<std::uint64_t>(std::numeric_limits<std::streamoff>::max() / 2)) return std::nullopt;
      block_at_ = at / kBlock * kBlock;
      block_.resize(kBlock);
      in_.clear();
      in_.seekg(static_cast<std::streamoff>(block_at_), std::ios::beg);
      in_.read(block_.data(), static_cast<std::streamsize>(kBlock));
      block_.resize(static_cast<std::size_t>(std::max<std::streamsize>(in_.gcount(), 0)));
      if (at >= block_at_ + block_.size()) return std::nullopt;
    }
    return static_cast<unsigned char>(block_[at - block_at_]);
  }

  std::ifstream in_;
  std::string block_;
  std::uint64_t block_at_ = 0;
};

// OpenEXR 3.1 reads a chunk that declares no bytes, or an uncompressed chunk shorter than its pixels, without an
// error: the pixels it lacks are whatever its buffer held (zeros, or other data of the process). Every chunk of a
// single-part scan-line or one-level tiled file is checked for that, from its chunk-offset table at byte `table_at`
// of `f`; what is wrong with the first bad one, empty when none is. Chunks whose offsets lie outside the file are
// left to OpenEXR (it says the file is truncated).
std::string check_exr_chunks(FileBytes& f, std::uint64_t table_at, const ExrPartLayout& layout, long long file_size) {
  constexpr long long kLargest = 1LL << 24;  // beyond the limits (refused after this) and safe from overflow
  if (layout.width <= 0 || layout.height <= 0 || layout.width > kLargest || layout.height > kLargest ||
      layout.bytes_per_pixel <= 0 || layout.bytes_per_pixel > kLargest)
    return {};
  const bool tiled = layout.type == "tiledimage";
  if (!tiled && layout.type != "scanlineimage") return {};
  const long long chunk_width = tiled ? layout.tile_width : layout.width;
  const long long chunk_height = tiled ? layout.tile_height : exr_lines_per_chunk(layout.compression);
  if (chunk_width <= 0 || chunk_height <= 0 || (tiled && layout.tile_level_mode != 0)) return {};
  const long long across = (layout.width + chunk_width - 1) / chunk_width;
  const long long down = (layout.height + chunk_height - 1) / chunk_height;  // across × down ≤ file size / 8
  // The whole table first, then the chunks (in the file's order, mostly): each read stays in f's current block.
  std::vector<std::uint64_t> offsets(static_cast<std::size_t>(across * down));
  for (std::size_t k = 0; k < offsets.size(); ++k) {
    const auto offset = f.uint(table_at + 8 * k, 8, false);
    if (!offset) return {};
    offsets[k] = *offset;
  }
  const int coordinates = tiled ? 16 : 4;  // tile x, y, level x, y; or the first scan line
  for (long long k = 0; k < across * down; ++k) {
    const std::uint64_t offset = offsets[static_cast<std::size_t>(k)];
    const auto bytes = static_cast<std::uint64_t>(file_size);
    if (offset < 8 || offset > bytes || bytes - offset < static_cast<std::uint64_t>(coordinates) + 4) continue;
    const auto declared = f.uint(offset + coordinates, 4, false);
    if (!declared) return {};
    const long long size = static_cast<std::int32_t>(*declared);
    const long long width = std::min(chunk_width, layout.width - (k % across) * chunk_width);
    const long long height = std::min(chunk_height, layout.height - (k / across) * chunk_height);
    const long long raw = width * height * layout.bytes_per_pixel;
    const bool uncompressed = layout.compression == 0 && !layout.subsampled;
    if (size <= 0 || (uncompressed && size != raw)) {
      return std::string("is truncated or corrupt: its " + std::string(tiled ? "tile" : "chunk of scan lines") +
                         " at byte " + std::to_string(offset) + " declares " + std::to_string(size) +
                         " bytes of pixels" +
                         (uncompressed ? ", not the " + std::to_string(raw) + " its " + std::to_string(width) + "×" +
                                             std::to_string(height) + " uncompressed pixels take"
                                       : ""));
    }
  }
  return {};
}

std::string first_bytes(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head;
}

// OpenImageIO 2.4 reads the IPTC block of a JPEG's Photoshop APP13 segment (libjpeg's saved copy of the segment,
// `length` bytes at `data`) by the sizes the block declares, without holding them to the segment (jpeginput.cpp's
// jpeg_decode_iptc, iptc.cpp's decode_iptc_iim): "Photoshop 3.0", NUL, "8BIM", resource 0x0404, 4 bytes, the block's
// 16-bit size, then records 0x1C, 1 or 2, a tag, a 16-bit size and that many bytes. A 698-byte file found by
// fuzz_image_header declared 88 bytes of IPTC in a 48-byte segment, and OpenImageIO copied 66 bytes from past the
// segment's buffer. InputError naming the file and the segment where what OpenImageIO would read does not fit.
void check_jpeg_photoshop_iptc(FileBytes& f, std::uint64_t data, std::uint64_t length, const std::string& path) {
  const auto byte_at = [&](std::uint64_t k) -> int {  // -1: past the file (libjpeg fills that with fake EOI bytes)
    const auto b = f.uint(data + k, 1, true);
    return b ? static_cast<int>(*b) : -1;
  };
  const auto refuse = [&](const std::string& why) {
    throw InputError(InputLocation::file(path),
                     "is corrupt: its Photoshop (APP13) segment at byte " + std::to_string(data - 4) + " " + why);
  };
  const auto cut_short = [&](std::uint64_t needed) {
    refuse("holds " + std::to_string(length) + " bytes, fewer than the " + std::to_string(needed) +
           " its IPTC header takes");
  };
  // As strcmp and strncmp read them: up to the first byte that differs (or the terminating NUL).
  constexpr std::string_view kPrefix("Photoshop 3.0\0008BIM", 18);
  for (std::uint64_t k = 0; k < kPrefix.size(); ++k) {
    if (k >= length) cut_short(k < 14 ? 14 : 18);  // every byte so far matched: the reader reads on
    if (byte_at(k) != static_cast<unsigned char>(kPrefix[k])) return;
  }
  if (length < 20) cut_short(20);
  if (byte_at(18) != 0x04 || byte_at(19) != 0x04) return;  // not the IPTC resource (1028)
  if (length < 26) cut_short(26);
  const auto size = f.uint(data + 24, 2, true);
  if (!size) return;
  if (26 + *size > length) {
    refuse("declares " + std::to_string(*size) + " bytes of IPTC data where it holds " + std::to_string(length - 26));
  }
  std::uint64_t at = 26;
  std::uint64_t left = *size;
  while (left >= 5 && byte_at(at) == 0x1c && (byte_at(at + 1) == 0x02 || byte_at(at + 1) == 0x01)) {
    const auto record = f.uint(data + at + 3, 2, true);
    if (!record) return;
    at += 5;
    left -= 5;
    if (*record > left) {
      refuse("has an IPTC record at byte " + std::to_string(data + at - 5) + " that declares " +
             std::to_string(*record) + " bytes where the block holds " + std::to_string(left));
    }
    at += *record;
    left -= *record;
  }
}

// libjpeg's frame header (SOFn) and first scan: a progressive frame, or a first scan of fewer components than the
// frame, makes it keep every block's 64 DCT coefficients (2 bytes each) of the whole image, allocated and zeroed
// when decompression starts, which OpenImageIO does when it opens the file (jdcoefct.c, jdinput.c).
std::optional<DeclaredImage> declared_jpeg(FileBytes& f, const std::string& path) {
  struct Component {
    long long h = 1;
    long long v = 1;
  };
  DeclaredImage image;
  std::vector<Component> components;
  bool progressive = false;
  // The frame as far as it is known; with whole-image coefficients when they are (or may yet be) held.
  const auto frame_so_far = [&](bool whole) -> std::optional<DeclaredImage> {
    if (components.empty()) return std::nullopt;
    if (whole) {
      long long max_h = 1;
      long long max_v = 1;
      for (const Component& c : components) {
        max_h = std::max(max_h, c.h);
        max_v = std::max(max_v, c.v);
      }
      const auto up = [](long long a, long long b) { return (a + b - 1) / b * b; };
      for (const Component& c : components) {
        const long long across = (image.width * c.h + 8 * max_h - 1) / (8 * max_h);
        const long long down = (image.height * c.v + 8 * max_v - 1) / (8 * max_v);
        image.whole_image_bytes += static_cast<std::uint64_t>(up(across, c.h) * up(down, c.v) * 128);
      }
      image.progressive_jpeg = true;
    }
    return image;
  };
  // As libjpeg's next_marker: bytes before a marker's 0xFF are skipped (with a warning), as are fill bytes after it
  // and a stuffed 0xFF 0x00 (a fuzzed file hid its 65500×65500 progressive frame behind such bytes).
  for (std::uint64_t at = 2;;) {  // after SOI
    const auto byte = f.uint(at, 1, true);
    if (!byte) return frame_so_far(progressive);
    if (*byte != 0xff) {
      ++at;
      continue;
    }
    auto marker = f.uint(at + 1, 1, true);
    while (marker && *marker == 0xff) marker = f.uint(++at + 1, 1, true);
    if (!marker) return frame_so_far(progressive);
    if (*marker == 0x00 || *marker == 0x01 || (*marker >= 0xd0 && *marker <= 0xd7)) {  // no segment
      at += 2;
      continue;
    }
    if (*marker == 0xd9) return frame_so_far(progressive);
    const auto length = f.uint(at + 2, 2, true);
    if (!length) return frame_so_far(progressive);
    if (*length < 2) {  // libjpeg skips nothing more than the length itself and reads on (skip_variable)
      at += 4;
      continue;
    }
    const std::uint64_t segment = at + 4;
    if (*marker == 0xed) check_jpeg_photoshop_iptc(f, segment, *length - 2, path);
    const bool frame = *marker >= 0xc0 && *marker <= 0xcf && *marker != 0xc4 && *marker != 0xc8 && *marker != 0xcc;
    if (frame && components.empty()) {
      const auto height = f.uint(segment + 1, 2, true);
      const auto width = f.uint(segment + 3, 2, true);
      const auto count = f.uint(segment + 5, 1, true);
      if (!height || !width || !count || *height == 0 || *width == 0 || *count == 0) return std::nullopt;
      image.width = static_cast<long long>(*width);
      image.height = static_cast<long long>(*height);
      progressive = (*marker & 0x03) == 0x02;  // SOF2, SOF6, SOF10, SOF14
      for (std::uint64_t k = 0; k < *count; ++k) {
        const auto sampling = f.uint(segment + 6 + 3 * k + 1, 1, true);
        const long long h = sampling ? static_cast<long long>(*sampling >> 4) : 0;
        const long long v = sampling ? static_cast<long long>(*sampling & 15) : 0;
        components.push_back({std::max(h, 1LL), std::max(v, 1LL)});  // libjpeg refuses 0 itself
      }
    } else if (*marker == 0xda) {  // start of scan: how many of the frame's components the first scan has
      const auto in_scan = f.uint(segment, 1, true);
      return frame_so_far(progressive || (in_scan && *in_scan < components.size()));
    }
    at = segment - 2 + *length;
  }
}

// A BMP's info header: OpenImageIO decodes an RLE-compressed one (RLE8, RLE4) whole, a byte a pixel, when it opens it.
std::optional<DeclaredImage> declared_bmp(FileBytes& f) {
  const auto info_size = f.uint(14, 4, false);
  if (!info_size) return std::nullopt;
  DeclaredImage image;
  if (*info_size == 12) {  // OS/2 BITMAPCOREHEADER: 16-bit sizes, no compression
    const auto width = f.uint(18, 2, false);
    const auto height = f.uint(20, 2, false);
    if (!width || !height) return std::nullopt;
    image.width = static_cast<long long>(*width);
    image.height = static_cast<long long>(*height);
  } else {
    const auto width = f.uint(18, 4, false);
    const auto height = f.uint(22, 4, false);
    const auto compression = f.uint(30, 4, false);
    if (!width || !height || !compression) return std::nullopt;
    image.width = static_cast<std::int32_t>(*width);
    image.height = std::abs(static_cast<long long>(static_cast<std::int32_t>(*height)));  // negative: top-down
    if (*compression == 1 || *compression == 2) {
      image.whole_image_bytes = static_cast<std::uint64_t>(std::max(image.width, 0LL) * image.height);
    }
  }
  if (image.width <= 0 || image.height <= 0) return std::nullopt;  // OpenImageIO says what is wrong
  return image;
}

// A TIFF's first image file directory (classic or BigTIFF, either byte order): its size and tiles.
std::optional<DeclaredImage> declared_tiff(FileBytes& f, const std::string& path) {
  const auto order = f.uint(0, 2, true);
  const bool big_endian = order && *order == 0x4d4d;
  const auto version = f.uint(2, 2, big_endian);
  if (!version || (*version != 42 && *version != 43)) return std::nullopt;
  const bool big = *version == 43;
  const auto ifd = big ? f.uint(8, 8, big_endian) : f.uint(4, 4, big_endian);
  const auto count = ifd ? f.uint(*ifd, big ? 8 : 2, big_endian) : std::nullopt;
  if (!count) return std::nullopt;
  const int entry_size = big ? 20 : 12;
  const int inline_bytes = big ? 8 : 4;
  // tag → its first value, of any integer type libtiff takes for a size; a tag's later copies are ignored, as libtiff
  // ignores them
  std::map<std::uint64_t, std::uint64_t> first_values;
  for (std::uint64_t k = 0; k < std::min<std::uint64_t>(*count, 4096); ++k) {
    const std::uint64_t entry = *ifd + (big ? 8 : 2) + k * entry_size;
    const auto tag = f.uint(entry, 2, big_endian);
    const auto type = f.uint(entry + 2, 2, big_endian);
    const auto values = f.uint(entry + 4, big ? 8 : 4, big_endian);
    if (!tag || !type || !values) return std::nullopt;
    // BYTE, SBYTE; SHORT, SSHORT; LONG, SLONG, IFD; LONG8, SLONG8, IFD8 (signed ones read as unsigned: a negative size
    // is refused as a huge one)
    const int size = *type == 1 || *type == 6                  ? 1
                     : *type == 3 || *type == 8                ? 2
                     : *type == 4 || *type == 9 || *type == 13 ? 4
                     : *type >= 16 && *type <= 18              ? 8
                                                               : 0;
    if (size == 0 || *values == 0) continue;
    const std::uint64_t value_at = entry + 4 + inline_bytes;
    std::optional<std::uint64_t> where = value_at;
    if (*values > static_cast<std::uint64_t>(inline_bytes / size)) where = f.uint(value_at, inline_bytes, big_endian);
    const auto value = where ? f.uint(*where, size, big_endian) : std::nullopt;
    if (value) first_values.emplace(*tag, *value);
  }
  const auto value = [&](std::uint64_t tag, std::uint64_t otherwise) {
    const auto it = first_values.find(tag);
    return it == first_values.end() ? otherwise : it->second;
  };
  DeclaredImage image;
  const std::uint64_t width = value(256, 0);
  const std::uint64_t height = value(257, 0);
  if (width == 0 || height == 0) return std::nullopt;  // libtiff says what is missing
  image.width = static_cast<long long>(std::min<std::uint64_t>(width, std::uint64_t{1} << 40));
  image.height = static_cast<long long>(std::min<std::uint64_t>(height, std::uint64_t{1} << 40));
  const std::uint64_t tile_width = value(322, 0);
  const std::uint64_t tile_height = value(323, 0);
  const std::uint64_t samples = std::max<std::uint64_t>(value(277, 1), 1);
  if (tile_width > 0 && tile_height > 0) {
    // tile_width × tile_height × samples × 4 > kMaxTiffTileFloatBytes, without overflow.
    const std::uint64_t pixels_allowed = static_cast<std::uint64_t>(kMaxTiffTileFloatBytes) / 4 / samples;
    if (tile_width > pixels_allowed || tile_height > pixels_allowed / tile_width) {
      throw InputError(InputLocation::file(path),
                       "TIFF tiles of " + std::to_string(tile_width) + "×" + std::to_string(tile_height) +
                           " pixels × " + std::to_string(samples) + " samples are larger than texwarp reads (at most " +
                           std::to_string(kMaxTiffTileFloatBytes >> 20) +
                           " MiB a tile as float, e.g. 2048×2048 RGBA); save the image with smaller tiles (e.g. "
                           "oiiotool in.tif --tile 64 64 -o out.tif)");
    }
  }
  return image;
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

std::vector<ExrPartSize> check_exr_header_sizes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  if (!in.read(head, 8) || std::string_view(head, 4) != kExrMagic) return {};
  std::error_code ec;
  const auto file_size = static_cast<long long>(std::filesystem::file_size(path, ec));
  const bool single_part_tiled = (static_cast<unsigned char>(head[5]) & 0x02) != 0;  // version flags, bit 9
  const bool single_part_deep = (static_cast<unsigned char>(head[5]) & 0x08) != 0;   // bit 11 (non-image)
  const bool multipart = (static_cast<unsigned char>(head[5]) & 0x10) != 0;          // bit 12
  const bool long_names = (static_cast<unsigned char>(head[5]) & 0x04) != 0;         // bit 10
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
  const auto read_u32 = [&] {
    unsigned char b[4];
    if (!in.read(reinterpret_cast<char*>(b), 4)) cut_short();
    return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
           static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24;
  };
  const auto read_i32 = [&] { return static_cast<long long>(static_cast<std::int32_t>(read_u32())); };
  std::vector<ExrPartSize> data_windows;
  std::string name;
  std::string type;
  do {
    read_name(name);
    if (name.empty()) break;  // the end of a multi-part file's list of headers
    const std::string part = multipart ? "part " + std::to_string(data_windows.size() + 1) + ": " : "";
    ExrPartLayout layout;
    while (!name.empty()) {
      read_name(type);
      const long long size = read_i32();
      const auto too_large = [&](long long bytes) {
        return bytes < 0 || bytes > file_size - static_cast<long long>(in.tellg());
      };
      const auto refuse = [&](const std::string& why) {
        std::string message = "not a valid OpenEXR file: " + part;
        message += "header attribute \"" + proto::utf8_prefix(name, 64) + "\" " + why;
        throw InputError(InputLocation::file(path), message);
      };
      if (too_large(size)) refuse("declares " + std::to_string(size) + " bytes, more than the file holds");
      // OpenEXR reads attributes of its own types by their type, not by the size they declare: a size that does not
      // fit its type would make it read other bytes as the next sizes than this check did. A valid file never has one.
      const long long start = static_cast<long long>(in.tellg());
      if (const auto fixed = kFixedAttributeSizes.find(type); fixed != kFixedAttributeSizes.end()) {
        if (size != fixed->second)
          refuse("of type " + type + " declares " + std::to_string(size) + " bytes, not " +
                 std::to_string(fixed->second));
        if (name == "dataWindow" && type == "box2i") {
          const long long x_min = read_i32();
          const long long y_min = read_i32();
          layout.width = read_i32() - x_min + 1;
          layout.height = read_i32() - y_min + 1;
        } else if (name == "tiles" && type == "tiledesc") {
          layout.tile_width = read_u32();
          layout.tile_height = read_u32();
          layout.tile_level_mode = in.get() & 0x0f;
        } else if (name == "compression" && type == "compression") {
          layout.compression = in.get();
        } else if (name == "chunkCount" && type == "int") {
          layout.chunk_count = read_i32();
        }
      } else if (type == "chlist") {  // read up to its terminating empty name
        std::string channel;
        for (read_name(channel); !channel.empty(); read_name(channel)) {
          const long long pixel_type = read_i32();  // UINT, HALF, FLOAT; OpenEXR refuses any other
          layout.bytes_per_pixel += pixel_type == 1 ? 2 : 4;
          ++layout.channels;
          in.seekg(4, std::ios::cur);  // linear flag, reserved
          const long long x_sampling = read_i32();
          const long long y_sampling = read_i32();
          if (x_sampling != 1 || y_sampling != 1) layout.subsampled = true;
        }
        if (static_cast<long long>(in.tellg()) - start != size)
          refuse("(a channel list) does not fill the bytes it declares");
      } else if (type == "preview") {  // pixels allocated from width × height
        // 8 + 4 × width × height == size, without the product (up to 2^66) overflowing.
        const long long width = read_u32();
        const long long height = read_u32();
        const long long pixels = (size - 8) / 4;
        const bool fills = size >= 8 && (size - 8) % 4 == 0 &&
                           (width == 0 || height == 0 ? pixels == 0 : pixels % width == 0 && pixels / width == height);
        if (!fills) refuse("(a preview) does not fill the bytes it declares");
      } else if (name == "type" && type == "string") {
        layout.type.resize(static_cast<std::size_t>(std::min(size, 16LL)));
        in.read(layout.type.data(), static_cast<std::streamsize>(layout.type.size()));
      }
      if (!in) cut_short();
      in.seekg(start + size, std::ios::beg);
      read_name(name);
    }
    // A single-part file's kind is its version flags' (OpenEXR overrides a "type" attribute from them), except deep
    // data, which only "type" names.
    if ((!multipart && !single_part_deep) || layout.type.empty())
      layout.type = single_part_tiled ? "tiledimage" : "scanlineimage";
    check_exr_part_layout(layout, file_size, path, part);
    if (layout.width != kNoDataWindow) {  // a single part's chunk-offset table follows its header
      std::string bad_chunk;
      if (const std::streamoff table_at = in.tellg(); !multipart && table_at >= 0) {
        FileBytes f(path);
        bad_chunk = check_exr_chunks(f, static_cast<std::uint64_t>(table_at), layout, file_size);
      }
      data_windows.push_back({layout.width, layout.height, layout.channels, std::move(bad_chunk)});
    }
  } while (multipart);
  return data_windows;
}

namespace {

// Whether the chunk whose 4 type bytes are `type` and whose `length` data bytes `in` is at (then its CRC) has the CRC
// the file gives it (zlib's crc32 over type and data, as the PNG specification defines it).
bool png_chunk_crc_matches(std::ifstream& in, const unsigned char* type, long long length) {
  uLong crc = crc32(0L, type, 4);
  std::array<unsigned char, 1 << 16> block{};
  for (long long left = length; left > 0;) {
    const auto n = static_cast<std::streamsize>(std::min<long long>(left, block.size()));
    if (!in.read(reinterpret_cast<char*>(block.data()), n)) return false;
    crc = crc32(crc, block.data(), static_cast<uInt>(n));
    left -= n;
  }
  unsigned char stored[4];
  if (!in.read(reinterpret_cast<char*>(stored), 4)) return false;
  const auto given = static_cast<std::uint32_t>(stored[0]) << 24 | static_cast<std::uint32_t>(stored[1]) << 16 |
                     static_cast<std::uint32_t>(stored[2]) << 8 | static_cast<std::uint32_t>(stored[3]);
  return given == static_cast<std::uint32_t>(crc);
}

}  // namespace

void check_png_chunks(const std::string& path, bool image_data) {
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
    const auto length =
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
    if (image_data && type == "IDAT" && !png_chunk_crc_matches(in, h + 4, length)) {
      refuse("the IDAT chunk at byte " + std::to_string(at) + " fails its CRC check: its pixel data are damaged");
    }
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

std::optional<DeclaredImage> declared_image(const std::string& path) {
  const std::string format = sniff_image_format(path);
  FileBytes f(path);
  const auto first = f.uint(0, 2, true);
  // OpenImageIO's JPEG reader takes a file that starts with SOI (libjpeg skips stray bytes after it); its BMP reader
  // the OS/2 magics too.
  if (first && *first == 0xffd8) return declared_jpeg(f, path);
  constexpr std::uint64_t kBmpMagics[] = {0x424d, 0x4241, 0x4349, 0x4350, 0x4943, 0x5054};  // BM BA CI CP IC PT
  if (first && std::find(std::begin(kBmpMagics), std::end(kBmpMagics), *first) != std::end(kBmpMagics))
    return declared_bmp(f);
  if (format == "tiff") return declared_tiff(f, path);
  return std::nullopt;
}

}  // namespace texwarp
