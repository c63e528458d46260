// The gate in front of OpenImageIO for untrusted files: which reader may open a file (by its first bytes, for the
// files without an extension that uploads and inline images are), and the sizes a file declares checked against the
// file before a decoder allocates them: OpenEXR headers (only headers OpenEXR cannot read otherwise than this check:
// names of at most 31 or 255 characters, sizes that fit their types, channel lists and previews that fill theirs;
// chunk-offset tables the file holds, tiles of a bounded size) and PNG chunks; WebP canvas sizes and OpenEXR data
// windows, read before OpenImageIO allocates from them.
#pragma once

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
// made it take 1.2 GB). The data window sizes of its parts, for the caller to hold to its limits; empty for files that
// are not OpenEXR.
std::vector<std::pair<long long, long long>> check_exr_header_sizes(const std::string& path);

// InputError naming the file when a PNG chunk declares more bytes than the file holds after it, or its type is not
// four ASCII letters (libpng 1.6 allocates a text, eXIf or sPLT chunk's declared length before reading it: a 60-byte
// file made it take 1.3 GB). Walks every chunk up to IEND; no-op for files that are not PNG.
void check_png_chunk_sizes(const std::string& path);

// A WebP file's canvas size as its first chunk (VP8, VP8L or VP8X) declares it; nullopt for other files or a header
// too short to say. OpenImageIO decodes a WebP image whole, as RGBA bytes, when it opens one: this is what the
// caller checks before that allocation.
std::optional<std::pair<long long, long long>> webp_canvas_size(const std::string& path);

}  // namespace texwarp
