// The gate in front of OpenImageIO for untrusted files: which reader may open a file (by its first bytes, for the
// files without an extension that uploads and inline images are), and the sizes a file declares checked against the
// file before a decoder allocates them: OpenEXR headers (only headers OpenEXR cannot read otherwise than this check:
// names of at most 31 or 255 characters, sizes that fit their types, channel lists and previews that fill theirs;
// chunk-offset tables the file holds, tiles of a bounded size) and PNG chunks; WebP canvas sizes, OpenEXR data
// windows and channel lists, JPEG frames, BMP headers and TIFF tiles, read before OpenImageIO allocates from them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace texwarp {

// The OpenImageIO format name ("png", "jpeg", "tiff", "openexr", "bmp", "webp", "hdr") of the file by its magic
// bytes; empty when it is none of these.
std::string sniff_image_format(const std::string& path);

// The most bytes one OpenEXR tile may declare (over its channels). OpenEXR allocates buffers of whole tiles when it
// opens a tiled file, before reading any; common tiles (16² to 512²) take at most 4 MiB.
inline constexpr long long kMaxExrTileBytes = 64LL << 20;

// InputError naming the file (and part) when an OpenEXR header declares more than the file holds or than texwarp
// reads, before OpenEXR 3.1 allocates it: an attribute's bytes (a 166-byte file made it take 1.9 GB), the table of
// chunk offsets its data window and tiles or scan-line blocks imply, or a tile over kMaxExrTileBytes (an 884-byte file
// made it take 1.2 GB). The data window sizes and channel counts of its parts, for the caller to hold to its limits
// (OpenEXR allocates buffers of whole blocks of scan lines over every channel when it opens a part: 600 channels
// of a 32768-pixel line made it ask for 12 buffers of 1.2 GB); empty for files that are not OpenEXR.
struct ExrPartSize {
  long long width = 0;  // of the data window
  long long height = 0;
  int channels = 0;
  // What is wrong with the first chunk of pixels that declares no bytes, or (uncompressed) other than its pixels
  // take: OpenEXR 3.1 reads such a chunk without an error, from whatever its buffer held. Single-part files only;
  // empty when no chunk is wrong. The caller refuses it after the limits.
  std::string bad_chunk;
};
std::vector<ExrPartSize> check_exr_header_sizes(const std::string& path);

// InputError naming the file when a PNG chunk declares more bytes than the file holds after it, or its type is not
// four ASCII letters (libpng 1.6 allocates a text, eXIf or sPLT chunk's declared length before reading it: a 60-byte
// file made it take 1.3 GB), or, with `image_data`, an IDAT chunk's CRC does not match its data (damaged pixels,
// found when the header is read, before a job or command spends its warp on them; a decode leaves that to libpng).
// Walks every chunk up to IEND (with `image_data` reading the image data once); no-op for files that are not PNG.
void check_png_chunks(const std::string& path, bool image_data);

// A WebP file's canvas size as its first chunk (VP8, VP8L or VP8X) declares it; nullopt for other files or a header
// too short to say. OpenImageIO decodes a WebP image whole, as RGBA bytes, when it opens one: this is what the
// caller checks before that allocation.
std::optional<std::pair<long long, long long>> webp_canvas_size(const std::string& path);

// The most bytes one TIFF tile may take as float. OpenImageIO converts a whole tile at a time to float, beside two
// copies in the file's samples (a 4 KiB file declaring 4096×4096 RGBA tiles made it take 390 MB; 65520×65520 tiles,
// 12.8 GB); common tiles (16² to 1024², RGBA) take at most 16 MiB.
inline constexpr long long kMaxTiffTileFloatBytes = 64LL << 20;

// What a JPEG, BMP or TIFF file's header declares, read before OpenImageIO opens the file: its decoder allocates
// from these when it opens it (a 1 KiB progressive JPEG declaring 65500×65500 pixels made libjpeg take 12.7 GB, an
// RLE BMP of 32768×32768, 1.1 GB), so the caller holds them to its limits first.
struct DeclaredImage {
  long long width = 0;
  long long height = 0;
  // What the decoder holds whole while it reads the image: a progressive (or multi-scan) JPEG's DCT coefficients,
  // an RLE-compressed BMP's decoded pixels; 0 for other files.
  std::uint64_t whole_image_bytes = 0;
  bool progressive_jpeg = false;
};
// A progressive JPEG's coefficients are held whole from the moment the file is opened: at most this many bytes
// (about 44 Mpx of 4:4:4 colour, 89 Mpx of 4:2:0), as for WebP images (kMaxWebpDecodeBytes).
inline constexpr std::uint64_t kMaxJpegCoefficientBytes = std::uint64_t{256} << 20;
// nullopt for other files, and for headers too short or odd to say (the decoder then says what is wrong).
// InputError naming the file when a TIFF's tiles are larger than kMaxTiffTileFloatBytes as float, or when a JPEG's
// Photoshop (APP13) segment declares an IPTC block or record larger than the segment (OpenImageIO 2.4 would read
// past it).
std::optional<DeclaredImage> declared_image(const std::string& path);

}  // namespace texwarp
