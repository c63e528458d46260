// The C ABI between core and the image module (libtexwarp_image_oiio.so: every format but PNG, through
// OpenImageIO), loaded with dlopen on first need. Both sides include this header; a change of any signature or
// struct here bumps TEXWARP_IMAGE_MODULE_ABI_VERSION, and core refuses a module built for another version.
#pragma once

// A C header (the module's ABI): C's typedefs, (void) and <stddef.h>, and the ABI's upper-case names are meant.
// NOLINTBEGIN(modernize-*, readability-identifier-naming)
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TEXWARP_IMAGE_MODULE_ABI_VERSION 6
// The one symbol the module exports: returns its table of entry points (static storage, never freed).
#define TEXWARP_IMAGE_MODULE_ENTRY "texwarp_image_module_v1"

// What an entry point reports. kInput: the file is at fault (the message says how, without the file's path: the
// caller names the file); kFailure: anything else (an output that cannot be written, an internal error).
enum { TEXWARP_IMAGE_OK = 0, TEXWARP_IMAGE_INPUT_ERROR = 1, TEXWARP_IMAGE_FAILURE = 2 };

// A message buffer the module writes a NUL-terminated text into (truncated to fit).
typedef struct TexwarpImageMessage {
  char text[1024];
} TexwarpImageMessage;

// An open file's header. format: the values of proto::PixelFormat; band_rows: read_rows takes row ranges that start
// at a multiple of it (a row of tiles), the last one ending at height; color_space: the file's
// "oiio:ColorSpace" (NUL-terminated, truncated to fit; empty when the file declares none).
typedef struct TexwarpImageInfo {
  int width;
  int height;
  int channels;
  int alpha_channel;
  int format;
  int band_rows;
  char color_space[64];
} TexwarpImageInfo;

typedef struct TexwarpImageReader TexwarpImageReader;  // opaque

typedef struct TexwarpImageModule {
  int abi_version;     // TEXWARP_IMAGE_MODULE_ABI_VERSION
  size_t struct_size;  // sizeof(TexwarpImageModule) as the module was built
  // The decoder library and its version, for messages ("OpenImageIO 2.4.7").
  const char* (*library_version)(void);
  // Opens `path` with the one reader that `format` names (an OpenImageIO format name), or, when `format` is empty,
  // the reader that takes the file's extension, and reads its header (the caller checks it against its limits
  // before reading rows). NULL, a status and a message on failure.
  TexwarpImageReader* (*open_reader)(const char* path, const char* format, TexwarpImageInfo* info, int* status,
                                     TexwarpImageMessage* message);
  // Decodes rows [y_begin, y_end) as float, all channels interleaved, into `out`. Any decoder error or warning is
  // TEXWARP_IMAGE_INPUT_ERROR ("is truncated or corrupt: ...").
  int (*read_rows)(TexwarpImageReader* reader, int y_begin, int y_end, float* out, TexwarpImageMessage* message);
  // Closes the file, reporting what the decoder said at its end; the reader is freed either way.
  int (*close_reader)(TexwarpImageReader* reader, TexwarpImageMessage* message);
  // Writes width×height×channels floats to `path` in the format its extension names, stored as `format`
  // (proto::PixelFormat) where the file format holds it, with `compression` (proto::Compression) for TIFF and EXR.
  // `stored_format`, `stored_channels`: what the file holds, read back from it (the writer's nearest to `format`: an
  // EXR's uint8 is half; a JPEG holds 1 or 3 channels, alpha dropped).
  int (*write_image)(const char* path, int width, int height, int channels, int alpha_channel, int format,
                     int compression, const float* pixels, int* stored_format, int* stored_channels,
                     TexwarpImageMessage* message);
  // Converts `count` pixels of `channels` floats (alpha, if any, at `alpha_channel`, −1 for none; colour
  // unassociated) in place from colour space `from` to `to` through OpenColorIO, with OpenImageIO's ColorConfig: the
  // config $OCIO names, else OpenImageIO's built-in one. A name may be a colour space, an alias or a role
  // ("scene_linear"). count 0 only checks the names. TEXWARP_IMAGE_INPUT_ERROR when the config knows neither as a
  // space: the message names it and lists the config's spaces.
  int (*convert_colors)(const char* from, const char* to, float* pixels, size_t count, int channels, int alpha_channel,
                        TexwarpImageMessage* message);
  // Writes a render-ready texture to `path` through OpenImageIO's make_texture: tiled, MIP-mapped down to 1×1, a TIFF
  // (.tx, .tif, .tiff) or an OpenEXR file (.exr) by the extension, stored as `format` with `compression` as
  // write_image, `color_space` (NUL-terminated, may be empty) recorded as its "oiio:ColorSpace". `stored_format`,
  // `stored_channels`, `tile_width` and `mip_levels`: what the file holds, read back from it.
  int (*write_texture)(const char* path, int width, int height, int channels, int alpha_channel, int format,
                       int compression, const float* pixels, const char* color_space, int* stored_format,
                       int* stored_channels, int* tile_width, int* mip_levels, TexwarpImageMessage* message);
  // 1 when the OpenColorIO config $OCIO names marks `name` (a colour space, an alias or a role) as data (its
  // `isdata`: values, not colour), else 0: also for a name it does not know, without $OCIO (OpenImageIO's built-in
  // config has no data spaces) and for a config that does not load (convert_colors reports that).
  int (*is_data_color_space)(const char* name);
} TexwarpImageModule;

typedef const TexwarpImageModule* (*TexwarpImageModuleEntry)(void);

#ifdef __cplusplus
}
#endif
// NOLINTEND(modernize-*, readability-identifier-naming)
