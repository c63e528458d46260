// Image files through OpenImageIO with header checks and atomic writes: see image_io.hpp.
#include "texwarp/core/image_io.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <OpenImageIO/imageio.h>

#include "texwarp/core/atomic_file.hpp"
#include "texwarp/core/image_format_gate.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

// OpenImageIO's "compression" for an output format (PNG's level is its own attribute).
const char* compression_name(Compression compression, const char* format) {
  const bool exr = std::strcmp(format, "openexr") == 0;
  switch (compression) {
    case Compression::kNone:
      return "none";
    case Compression::kSmall:
      return "zip:9";
    case Compression::kFast:
      break;
  }
  return exr ? "piz" : "zip:1";
}

PixelFormat from_type(OIIO::TypeDesc t) {
  switch (t.basetype) {
    case OIIO::TypeDesc::UINT8:
    case OIIO::TypeDesc::INT8:
      return PixelFormat::kUint8;
    case OIIO::TypeDesc::UINT16:
    case OIIO::TypeDesc::INT16:
      return PixelFormat::kUint16;
    case OIIO::TypeDesc::HALF:
      return PixelFormat::kHalf;
    default:
      return PixelFormat::kFloat;
  }
}

OIIO::TypeDesc to_type(PixelFormat f) {
  switch (f) {
    case PixelFormat::kUint8:
      return OIIO::TypeDesc::UINT8;
    case PixelFormat::kUint16:
      return OIIO::TypeDesc::UINT16;
    case PixelFormat::kHalf:
      return OIIO::TypeDesc::HALF;
    case PixelFormat::kFloat:
      return OIIO::TypeDesc::FLOAT;
  }
  return OIIO::TypeDesc::FLOAT;
}

// What a decoder said, without the file's path (it may be a server's own layout): the location names the file.
std::string without_path(std::string text, const std::string& path) {
  for (auto at = text.find(path); !path.empty() && at != std::string::npos; at = text.find(path, at)) {
    text.replace(at, path.size(), "the file");
  }
  return text;
}

// The OpenImageIO format whose reader takes files with this extension (".png", case-insensitive); empty if none.
std::string format_of_extension(const std::string& extension) {
  std::string ext = extension.substr(1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const auto& [format, extensions] : OIIO::get_extension_map()) {
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end()) return format;
  }
  return {};
}

// OpenImageIO decodes a WebP image whole when it opens it: its canvas is held to the limits, and to what one decode
// may take, before that allocation.
void check_webp_canvas(const std::string& path, const ImageLimits& limits) {
  const auto canvas = webp_canvas_size(path);
  if (!canvas) return;
  const auto [width, height] = *canvas;
  const std::string size = std::to_string(width) + "×" + std::to_string(height);
  if (width > limits.max_dimension || height > limits.max_dimension || width * height > limits.max_pixels) {
    throw InputError(InputLocation::file(path), "WebP image is " + size + ", beyond the limits of " +
                                                    std::to_string(limits.max_dimension) + " pixels on a side and " +
                                                    std::to_string(limits.max_pixels) + " pixels");
  }
  if (width * height * 4 > static_cast<long long>(kMaxWebpDecodeBytes)) {
    throw InputError(InputLocation::file(path), "WebP image is " + size + ": WebP images are read whole, and at most " +
                                                    std::to_string(kMaxWebpDecodeBytes / 4 / 1024 / 1024) +
                                                    " Mpx of them; convert larger ones to PNG, TIFF or OpenEXR");
  }
}

std::unique_ptr<OIIO::ImageInput> open_input(const std::string& path, const ImageLimits& limits) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(InputLocation::file(path), "no such file");
  if (fs::is_directory(path, ec)) throw InputError(InputLocation::file(path), "is a directory, not an image");
  check_exr_header_sizes(path);
  check_png_chunk_sizes(path);
  check_webp_canvas(path, limits);
  // One reader only, never OpenImageIO's fall-back through every reader it has (DICOM, video, raw camera files,
  // WebP's whole-file decode...) on untrusted bytes that the first reader refused: the reader the extension names,
  // or, for a file without one (an upload, an inline image), the reader its first bytes name.
  // Created by its format's name: created from a file name, OpenImageIO would let any reader claim the bytes.
  const std::string extension = fs::path(path).extension().string();
  const std::string format = extension.empty() ? sniff_image_format(path) : format_of_extension(extension);
  if (format.empty()) {
    throw InputError(InputLocation::file(path),
                     extension.empty()
                         ? "not an image texwarp reads: expected PNG, JPEG, TIFF, OpenEXR, BMP, WebP or Radiance HDR"
                         : "cannot read as an image: no image reader takes the extension " +
                               proto::utf8_prefix(extension, 32));
  }
  std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::create(format);
  if (!in) {
    std::string why = without_path(OIIO::geterror(), path);
    throw InputError(InputLocation::file(path), "cannot read as an image" + (why.empty() ? std::string() : ": " + why));
  }
  OIIO::ImageSpec spec;
  if (!in->open(path, spec)) {
    std::string why = without_path(in->geterror(), path);
    throw InputError(InputLocation::file(path),
                     "cannot read as " + std::string(in->format_name()) + (why.empty() ? std::string() : ": " + why));
  }
  return in;
}

ImageHeader check_header(const OIIO::ImageSpec& spec, const std::string& path, const ImageLimits& limits) {
  if (spec.width <= 0 || spec.height <= 0) throw InputError(InputLocation::file(path), "image has no pixels");
  if (spec.depth > 1) {
    throw InputError(InputLocation::file(path),
                     "image is a volume (" + std::to_string(spec.depth) + " slices); only 2D images are supported");
  }
  if (spec.width > limits.max_dimension || spec.height > limits.max_dimension) {
    throw InputError(InputLocation::file(path), "image is " + std::to_string(spec.width) + "×" +
                                                    std::to_string(spec.height) + ", larger than the limit of " +
                                                    std::to_string(limits.max_dimension) + " pixels on a side");
  }
  const long long pixels = static_cast<long long>(spec.width) * spec.height;
  if (pixels > limits.max_pixels) {
    throw InputError(InputLocation::file(path), "image has " + std::to_string(pixels) +
                                                    " pixels, more than the limit of " +
                                                    std::to_string(limits.max_pixels));
  }
  if (spec.nchannels < 1 || spec.nchannels > limits.max_channels) {
    throw InputError(InputLocation::file(path), "image has " + std::to_string(spec.nchannels) + " channels; 1 to " +
                                                    std::to_string(limits.max_channels) + " are supported");
  }
  ImageHeader h;
  h.width = spec.width;
  h.height = spec.height;
  h.channels = spec.nchannels;
  h.alpha_channel = spec.alpha_channel;
  h.format = from_type(spec.format);
  return h;
}

// The first line of what the decoder said (libtiff, for one, repeats itself for every strip).
std::string first_line(const std::string& text) {
  const std::string line = text.substr(0, text.find('\n'));
  return line.empty() ? "the decoder stopped without saying why" : line;
}

// A read that failed, or that "succeeded" while the decoder reported a problem (libjpeg fills a truncated JPEG
// with grey and only warns; libtiff skips strips it cannot read), is an error: never a partly decoded image.
void check_decoded(OIIO::ImageInput& in, bool ok, const std::string& path) {
  if (ok && !in.has_error()) return;
  throw InputError(InputLocation::file(path),
                   "is truncated or corrupt: " + without_path(first_line(in.geterror()), path));
}

}  // namespace

ImageHeader read_image_header(const std::string& path, const ImageLimits& limits) {
  auto in = open_input(path, limits);
  return check_header(in->spec(), path, limits);
}

Image read_image(const std::string& path, const ImageLimits& limits, ImageHeader* header) {
  auto in = open_input(path, limits);
  const OIIO::ImageSpec spec = in->spec();
  const ImageHeader h = check_header(spec, path, limits);
  Image image;
  image.width = h.width;
  image.height = h.height;
  image.channels = h.channels;
  image.alpha_channel = h.alpha_channel;
  const std::size_t row_values = static_cast<std::size_t>(h.width) * static_cast<std::size_t>(h.channels);
  // Address space for the whole image, not memory: pages are committed as decoded rows are written into them,
  // so a header that lies costs what the file's bytes really held.
  try {  // address space only: pages are committed band by band as the decoder fills them
    image.pixels.reserve(row_values * static_cast<std::size_t>(h.height));
  } catch (const std::bad_alloc&) {  // no overcommit (vm.overcommit_memory=2, RLIMIT_AS) and not enough memory
    throw InputError(InputLocation::file(path), "not enough memory to decode this " + std::to_string(h.width) + "×" +
                                                    std::to_string(h.height) + " image (" + std::to_string(h.channels) +
                                                    " channels as float)");
  }
  const bool tiled = spec.tile_width > 0 && spec.tile_height > 0;
  const int band = tiled ? spec.tile_height : 1;  // read_tiles wants whole rows of tiles
  const std::size_t band_bytes = row_values * sizeof(float) * static_cast<std::size_t>(band);
  const int rows = band * static_cast<int>(std::max<std::size_t>(1, kImageDecodeChunkBytes / band_bytes));
  for (int y = 0; y < h.height; y += rows) {
    const int end = std::min(h.height, y + rows);
    const std::size_t done = image.pixels.size();
    image.pixels.resize(done + row_values * static_cast<std::size_t>(end - y));
    float* rows_out = image.pixels.data() + done;
    const bool ok = tiled ? in->read_tiles(0, 0, spec.x, spec.x + h.width, spec.y + y, spec.y + end, spec.z, spec.z + 1,
                                           0, h.channels, OIIO::TypeDesc::FLOAT, rows_out)
                          : in->read_scanlines(0, 0, spec.y + y, spec.y + end, spec.z, 0, h.channels,
                                               OIIO::TypeDesc::FLOAT, rows_out);
    check_decoded(*in, ok, path);
  }
  check_decoded(*in, in->close(), path);
  if (header) *header = h;
  return image;
}

void write_image(const std::string& path, const Image& image, PixelFormat format) {
  write_image(path, image, format, ImageEncoding{});
}

void write_image(const std::string& path, const Image& image, PixelFormat format, const ImageEncoding& encoding,
                 ImageWriteTimes* times) {
  if (encoding.png_compression_level < 0 || encoding.png_compression_level > proto::kMaxPngCompressionLevel) {
    throw std::invalid_argument("write_image: PNG compression level out of range");
  }
  const auto start = std::chrono::steady_clock::now();
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * image.channels) {
    throw std::invalid_argument("write_image: inconsistent image");
  }
  auto out = OIIO::ImageOutput::create(path);
  if (!out) {
    std::string why = without_path(OIIO::geterror(), path);
    throw InputError(InputLocation::file(path), "cannot write this image format (is the extension right?)" +
                                                    (why.empty() ? std::string() : ": " + why));
  }
  const std::string temp = temporary_path_for(path);
  OIIO::ImageSpec spec(image.width, image.height, image.channels, to_type(format));
  spec.alpha_channel = image.alpha_channel;
  spec.attribute("png:compressionLevel", encoding.png_compression_level);
  spec.attribute("compression", compression_name(encoding.compression, out->format_name()));
  try {
    if (!out->open(temp, spec)) throw std::runtime_error("cannot open " + path + ": " + out->geterror());
    if (!out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data())) {
      throw std::runtime_error("cannot write " + path + ": " + out->geterror());
    }
    if (!out->close()) throw std::runtime_error("cannot finish " + path + ": " + out->geterror());
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
  const auto encoded = std::chrono::steady_clock::now();
  publish_file(temp, path);
  if (times) {
    times->encode_s = std::chrono::duration<double>(encoded - start).count();
    times->write_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - encoded).count();
  }
}

}  // namespace texwarp
