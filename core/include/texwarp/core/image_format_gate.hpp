// The gate in front of OpenImageIO for untrusted files: which reader may open a file (by its first bytes, for the
// files without an extension that uploads and inline images are), and the sizes a file declares checked against the
// file before a decoder allocates them: OpenEXR header attributes (only headers OpenEXR cannot read otherwise than
// this check: names of at most 31 or 255 characters, sizes that fit their types, channel lists and previews that fill
// theirs) and PNG chunks; WebP canvas sizes, read before OpenImageIO decodes the whole image to open it.
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace texwarp {

// The OpenImageIO format name ("png", "jpeg", "tiff", "openexr", "bmp", "webp", "hdr") of the file by its magic
// bytes; empty when it is none of these.
std::string sniff_image_format(const std::string& path);

// InputError naming the file when an OpenEXR header attribute declares more bytes than the file holds (OpenEXR 3.1
// would allocate them: a 166-byte file made it take 1.9 GB). No-op for files that are not OpenEXR.
void check_exr_header_sizes(const std::string& path);

// InputError naming the file when a PNG chunk declares more bytes than the file holds after it, or its type is not
// four ASCII letters (libpng 1.6 allocates a text, eXIf or sPLT chunk's declared length before reading it: a 60-byte
// file made it take 1.3 GB). Walks every chunk up to IEND; no-op for files that are not PNG.
void check_png_chunk_sizes(const std::string& path);

// A WebP file's canvas size as its first chunk (VP8, VP8L or VP8X) declares it; nullopt for other files or a header
// too short to say. OpenImageIO decodes a WebP image whole, as RGBA bytes, when it opens one: this is what the
// caller checks before that allocation.
std::optional<std::pair<long long, long long>> webp_canvas_size(const std::string& path);

}  // namespace texwarp
