// Image files: PNG through libpng, the rest through the OpenImageIO module; header checks, atomic writes: see
// image_io.hpp.
#include "texwarp/core/image_io.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <utility>
#include <vector>

#include "texwarp/core/atomic_file.hpp"
#include "texwarp/core/image_buffer.hpp"
#include "texwarp/core/image_format_gate.hpp"
#include "texwarp/core/image_module.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/png_codec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

// OpenImageIO decodes a WebP image whole when it opens it: its canvas is held to the limits, and to what one decode
// may take, before that allocation. The bytes of that decode (0 for other files).
std::uint64_t check_webp_canvas(const std::string& path, const ImageLimits& limits) {
  const auto canvas = webp_canvas_size(path);
  if (!canvas) return 0;
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
  return static_cast<std::uint64_t>(width * height * 4);
}

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// Which reader opens a file: PNG (libpng, here), or the module's reader for `module_format` (an OpenImageIO format
// name; empty: the one the extension names); what that reader holds of the whole image while it reads.
struct Reader {
  bool png = false;
  std::string module_format;
  std::uint64_t decoder_whole_image_bytes = 0;
};

// The sizes a JPEG, BMP or TIFF header declares, held to the limits before OpenImageIO opens the file and allocates
// from them; what its decoder will hold whole (a progressive JPEG's coefficients: bounded, as WebP's canvas is).
std::uint64_t check_declared_image(const std::string& path, const ImageLimits& limits) {
  const auto declared = declared_image(path);
  if (!declared) return 0;
  check_image_size(declared->width, declared->height, path, limits);
  if (declared->progressive_jpeg && declared->whole_image_bytes > kMaxJpegCoefficientBytes) {
    throw InputError(InputLocation::file(path),
                     "JPEG image is " + std::to_string(declared->width) + "×" + std::to_string(declared->height) +
                         " in progressive (or multi-scan) form, which is decoded whole: " +
                         format_bytes(declared->whole_image_bytes) + " of coefficients, more than texwarp's " +
                         format_bytes(kMaxJpegCoefficientBytes) +
                         "; convert it to a baseline JPEG, PNG or TIFF (e.g. oiiotool in.jpg -o out.png)");
  }
  return declared->whole_image_bytes;
}

// The gate in front of every decoder (image_format_gate.hpp), then the one reader the file gets: the one its
// extension names or, for a file without one (an upload, an inline image), the one its first bytes name.
// `decoding`: the pixels are decoded next, and the decoder checks a PNG's image data itself (libpng's CRCs).
Reader choose_reader(const std::string& path, const ImageLimits& limits, bool decoding) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(InputLocation::file(path), "no such file");
  if (fs::is_directory(path, ec)) throw InputError(InputLocation::file(path), "is a directory, not an image");
  const std::vector<ExrPartSize> exr_parts = check_exr_header_sizes(path);
  if (!exr_parts.empty()) {  // the part texwarp reads (OpenImageIO opens no other)
    check_image_size(exr_parts.front().width, exr_parts.front().height, path, limits);
    check_image_channels(exr_parts.front().channels, path, limits);
    if (!exr_parts.front().bad_chunk.empty()) throw InputError(InputLocation::file(path), exr_parts.front().bad_chunk);
  }
  check_png_chunks(path, !decoding);
  std::uint64_t whole_image_bytes = check_webp_canvas(path, limits);
  whole_image_bytes += check_declared_image(path, limits);
  const std::string extension = lowercase(fs::path(path).extension().string());
  if (!extension.empty()) return Reader{extension == ".png", {}, whole_image_bytes};
  const std::string format = sniff_image_format(path);
  if (format.empty()) {
    throw InputError(InputLocation::file(path),
                     "not an image texwarp reads: expected PNG, JPEG, TIFF, OpenEXR, BMP, WebP or Radiance HDR");
  }
  return Reader{format == "png", format, whole_image_bytes};
}

// "reading .exr", "reading a tiff file": what needs the module, for its message when it is missing.
std::string reading_what(const std::string& path, const Reader& reader) {
  const std::string extension = fs::path(path).extension().string();
  return extension.empty() ? "reading a " + reader.module_format + " file"
                           : "reading " + proto::utf8_prefix(extension, 32);
}

[[noreturn]] void module_failed(int status, const std::string& path, const TexwarpImageMessage& message) {
  if (status == TEXWARP_IMAGE_INPUT_ERROR) throw InputError(InputLocation::file(path), message.text);
  throw std::runtime_error(path + ": " + message.text);
}

// A file opened by the module's reader, closed when this goes (a constructor that throws included).
class ModuleReader {
 public:
  ModuleReader(const std::string& path, const Reader& reader, const ImageLimits& limits)
      : path_(path), handle_{&image_module(reading_what(path, reader), path), nullptr} {
    TexwarpImageMessage message{};
    TexwarpImageInfo info{};
    int status = TEXWARP_IMAGE_FAILURE;
    handle_.reader = handle_.module->open_reader(path.c_str(), reader.module_format.c_str(), &info, &status, &message);
    if (!handle_.reader) module_failed(status, path, message);
    header_.width = info.width;
    header_.height = info.height;
    header_.channels = info.channels;
    header_.alpha_channel = info.alpha_channel;
    header_.format = static_cast<PixelFormat>(info.format);
    header_.color_space.assign(info.color_space, strnlen(info.color_space, sizeof info.color_space));
    header_.decoder_whole_image_bytes = reader.decoder_whole_image_bytes;
    band_rows_ = std::max(1, info.band_rows);
    check_image_size(header_.width, header_.height, path, limits);
    check_image_channels(header_.channels, path, limits);
    if (band_rows_ > 1) {  // tiled: OpenImageIO reads a row of tiles in the file's samples, and the decoder's tiles
      // beside it, about as much again (measured: 8192×2048 RGBA files of 2048-row tiles took 111 MB (TIFF, 8-bit)
      // and 304 MB (OpenEXR, half) beyond the float image, against 64 and 128 MB for one such row).
      const std::uint64_t tile_row = static_cast<std::uint64_t>(header_.width) *
                                     static_cast<std::uint64_t>(std::min(band_rows_, header_.height)) *
                                     static_cast<std::uint64_t>(header_.channels) * bytes_per_value(header_.format);
      header_.decoder_whole_image_bytes += 2 * tile_row;
    }
  }

  const ImageHeader& header() const { return header_; }

  void read(Image& image, const RunControl& control) {
    const std::size_t row_values = static_cast<std::size_t>(header_.width) * static_cast<std::size_t>(header_.channels);
    const std::size_t band_bytes = row_values * sizeof(float) * static_cast<std::size_t>(band_rows_);
    const int rows = band_rows_ * static_cast<int>(std::max<std::size_t>(1, kImageDecodeChunkBytes / band_bytes));
    TexwarpImageMessage message{};
    for (int y = 0; y < header_.height; y += rows) {
      if (control.canceled()) throw CanceledError();  // (the reader is closed by its handle)
      const int end = std::min(header_.height, y + rows);
      const std::size_t done = image.pixels.size();
      image.pixels.resize(done + row_values * static_cast<std::size_t>(end - y));
      const int status = handle_.module->read_rows(handle_.reader, y, end, image.pixels.data() + done, &message);
      if (status != TEXWARP_IMAGE_OK) module_failed(status, path_, message);
    }
    const int status = handle_.module->close_reader(std::exchange(handle_.reader, nullptr), &message);
    if (status != TEXWARP_IMAGE_OK) module_failed(status, path_, message);
  }

 private:
  struct Handle {
    const TexwarpImageModule* module;
    TexwarpImageReader* reader;
    Handle(const TexwarpImageModule* m, TexwarpImageReader* r) : module(m), reader(r) {}
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    ~Handle() {
      TexwarpImageMessage ignored{};
      if (reader) module->close_reader(reader, &ignored);
    }
  };

  std::string path_;
  Handle handle_;
  ImageHeader header_;
  int band_rows_ = 1;
};

}  // namespace

void check_image_size(long long width, long long height, const std::string& path, const ImageLimits& limits) {
  if (width <= 0 || height <= 0) throw InputError(InputLocation::file(path), "image has no pixels");
  if (width > limits.max_dimension || height > limits.max_dimension) {
    throw InputError(InputLocation::file(path), "image is " + std::to_string(width) + "×" + std::to_string(height) +
                                                    ", larger than the limit of " +
                                                    std::to_string(limits.max_dimension) + " pixels on a side");
  }
  const long long pixels = width * height;
  if (pixels > limits.max_pixels) {
    throw InputError(InputLocation::file(path), "image has " + std::to_string(pixels) +
                                                    " pixels, more than the limit of " +
                                                    std::to_string(limits.max_pixels));
  }
}

void check_image_channels(int channels, const std::string& path, const ImageLimits& limits) {
  if (channels < 1 || channels > limits.max_channels) {
    throw InputError(InputLocation::file(path), "image has " + std::to_string(channels) + " channels; 1 to " +
                                                    std::to_string(limits.max_channels) + " are supported");
  }
}

Image reserve_image(const ImageHeader& header, const std::string& path) {
  Image image;
  image.width = header.width;
  image.height = header.height;
  image.channels = header.channels;
  image.alpha_channel = header.alpha_channel;
  try {  // address space only: pages are committed band by band as the decoder fills them
    reserve_pixels(image, static_cast<std::size_t>(header.width) * static_cast<std::size_t>(header.height) *
                              static_cast<std::size_t>(header.channels));
  } catch (const std::bad_alloc&) {  // no overcommit (vm.overcommit_memory=2, RLIMIT_AS) and not enough memory
    throw InputError(InputLocation::file(path), "not enough memory to decode this " + std::to_string(header.width) +
                                                    "×" + std::to_string(header.height) + " image (" +
                                                    std::to_string(header.channels) + " channels as float)");
  }
  return image;
}

ImageHeader read_image_header(const std::string& path, const ImageLimits& limits) {
  const Reader reader = choose_reader(path, limits, false);
  if (reader.png) return read_png_header(path, limits);
  return ModuleReader(path, reader, limits).header();
}

Image read_image(const std::string& path, const ImageLimits& limits, ImageHeader* header, const RunControl& control) {
  const Reader reader = choose_reader(path, limits, true);
  if (reader.png) return read_png(path, limits, header, control);
  ModuleReader in(path, reader, limits);
  Image image = reserve_image(in.header(), path);
  in.read(image, control);
  if (header) *header = in.header();
  return image;
}

WrittenImage write_image(const std::string& path, const Image& image, PixelFormat format) {
  return write_image(path, image, format, ImageEncoding{});
}

WrittenImage write_image(const std::string& path, const Image& image, PixelFormat format, const ImageEncoding& encoding,
                         ImageWriteTimes* times) {
  if (encoding.png_compression_level < 0 || encoding.png_compression_level > proto::kMaxPngCompressionLevel) {
    throw std::invalid_argument("write_image: PNG compression level out of range");
  }
  const auto start = std::chrono::steady_clock::now();
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * image.channels) {
    throw std::invalid_argument("write_image: inconsistent image");
  }
  const std::string extension = fs::path(path).extension().string();
  const bool png = lowercase(extension) == ".png";
  // The module first (it says whether it writes this extension), then the temporary file.
  const TexwarpImageModule* module =
      png ? nullptr : &image_module("writing " + proto::utf8_prefix(extension.empty() ? path : extension, 32), path);
  const std::string temp = temporary_path_for(path);
  WrittenImage stored{format, image.channels};  // PNG holds every channel count texwarp has (1 to 4)
  try {
    if (png) {
      stored.format = write_png(temp, path, image, format, encoding.png_compression_level);
    } else {
      TexwarpImageMessage message{};
      int stored_format = static_cast<int>(format);
      int stored_channels = image.channels;
      const int status = module->write_image(
          temp.c_str(), image.width, image.height, image.channels, image.alpha_channel, static_cast<int>(format),
          static_cast<int>(encoding.compression), image.pixels.data(), &stored_format, &stored_channels, &message);
      if (status == TEXWARP_IMAGE_INPUT_ERROR) throw InputError(InputLocation::file(path), message.text);
      if (status != TEXWARP_IMAGE_OK) throw std::runtime_error("cannot write " + path + ": " + message.text);
      stored = {static_cast<PixelFormat>(stored_format), stored_channels};
    }
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
  return stored;
}

}  // namespace texwarp
