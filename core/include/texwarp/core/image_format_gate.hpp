// The gate in front of OpenImageIO for untrusted files: which reader may open a file (by its first bytes, for the
// files without an extension that uploads and inline images are), and OpenEXR header sizes checked against the
// file before the EXR library allocates what they declare (only headers OpenEXR cannot read otherwise than this check:
// names of at most 31 or 255 characters, sizes that fit their types, channel lists and previews that fill theirs).
#pragma once

#include <string>

namespace texwarp {

// The OpenImageIO format name ("png", "jpeg", "tiff", "openexr", "bmp", "webp", "hdr") of the file by its magic
// bytes; empty when it is none of these.
std::string sniff_image_format(const std::string& path);

// InputError naming the file when an OpenEXR header attribute declares more bytes than the file holds (OpenEXR 3.1
// would allocate them: a 166-byte file made it take 1.9 GB). No-op for files that are not OpenEXR.
void check_exr_header_sizes(const std::string& path);

}  // namespace texwarp
