// Image files: PNG through libpng (png_codec.hpp), every other format through OpenImageIO in a module loaded on
// first need (image_module.hpp). Header checks before any pixel is read (untrusted input), decoding in bounded
// chunks with every decoder error (truncation included) an error, conversion to float, and atomic writes
// (temporary file, fsync, rename) so that no half-written image is ever left behind.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "texwarp/core/image.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/output_enums.hpp"

namespace texwarp {

// Storage type of pixel values in a file (names: proto/output_enums.hpp).
using proto::PixelFormat;

// read_image decodes about this many bytes of float pixels per call: at least one row (or one row of tiles).
inline constexpr std::size_t kImageDecodeChunkBytes = std::size_t{16} << 20;
// A WebP image is decoded whole (RGBA, 8 bits) when OpenImageIO opens it: at most this many bytes (64 Mpx).
inline constexpr std::size_t kMaxWebpDecodeBytes = std::size_t{256} << 20;

struct ImageLimits {
  long long max_pixels = 16384LL * 16384LL;
  int max_dimension = 32768;
  int max_channels = 4;
};

struct ImageHeader {
  int width = 0;
  int height = 0;
  int channels = 0;
  int alpha_channel = -1;
  PixelFormat format = PixelFormat::kUint8;  // nearest supported to the file's own
  // The colour space the file declares, as it names it (OpenImageIO's "oiio:ColorSpace"; a PNG's sRGB chunk is
  // "sRGB", a gAMA of 1.0 "linear", of 1/2.2 "sRGB"); empty when the file declares none.
  std::string color_space;
  // What the decoder holds beside the float image and its bands: an interlaced (Adam7) PNG's whole image in the
  // file's own samples, which libpng needs at once; a progressive JPEG's coefficients, a WebP's or RLE BMP's pixels
  // (image_format_gate.hpp); a tiled file's row of tiles, twice, in the file's samples; 0 for every other file.
  std::uint64_t decoder_whole_image_bytes = 0;
};

// The checks of a header every reader makes before decoding: InputError naming the file when the image has no
// pixels or is beyond the limits.
void check_image_size(long long width, long long height, const std::string& path, const ImageLimits& limits);
void check_image_channels(int channels, const std::string& path, const ImageLimits& limits);
// An empty image of the header's size with address space (not memory) reserved for its pixels, which a reader
// appends band by band; InputError naming the file when there is not even the address space.
Image reserve_image(const ImageHeader& header, const std::string& path);

// Reads only the header; InputError naming the file when it cannot be opened or exceeds the limits.
ImageHeader read_image_header(const std::string& path, const ImageLimits& limits = {});

// Reads the first subimage as float (alpha associated); checks the header against limits first. Pixels are
// decoded a band of rows (or of tiles) at a time, and memory is committed only for the rows actually decoded, so
// a file whose header promises more than its bytes hold fails having used what they held. Any error or warning
// of the decoder (a truncated file, a JPEG's premature end, a strip that cannot be read) is an InputError naming
// the file, "is truncated or corrupt: …": never a partly filled image. CanceledError before the next band once
// `control` is cancelled: a decode that is no longer wanted stops within a band of about kImageDecodeChunkBytes (an
// interlaced PNG's passes within a row; a format its decoder reads whole at the first band, a progressive JPEG or a
// WebP, only after that band).
Image read_image(const std::string& path, const ImageLimits& limits = {}, ImageHeader* header = nullptr,
                 const RunControl& control = {});

// How an output file is compressed (all lossless; names: proto/output_enums.hpp).
using proto::Compression;
struct ImageEncoding {
  int png_compression_level = proto::kDefaultPngCompressionLevel;  // zlib level 0–9 (png:compressionLevel)
  Compression compression = Compression::kFast;                    // TIFF and EXR ("compression")
};

// Where write_image's time went: the encoder writing the temporary file, then flushing and renaming it.
struct ImageWriteTimes {
  double encode_s = 0.0;
  double write_s = 0.0;
};

// What a written file holds: its pixel format and channels (a JPEG drops alpha: 3 channels of an RGBA image).
struct WrittenImage {
  PixelFormat format = PixelFormat::kUint8;
  int channels = 0;
  bool operator==(const WrittenImage&) const = default;
};

// Writes atomically; the file format follows the extension. InputError for an unknown extension. Stores `format`
// where the file format holds it, else its writer's nearest (PNG: 8 bits for half and float; EXR: half for uint8 and
// uint16; TIFF: float for half; JPEG: uint8, without alpha), and returns what the file holds: the one answer messages
// and reports give about a written image's pixel format and channels.
WrittenImage write_image(const std::string& path, const Image& image, PixelFormat format);
WrittenImage write_image(const std::string& path, const Image& image, PixelFormat format, const ImageEncoding& encoding,
                         ImageWriteTimes* times = nullptr);

}  // namespace texwarp
