// PNG through libpng, pixel for pixel as OpenImageIO 2.4 read and wrote it: see png_codec.hpp.
#include "texwarp/core/png_codec.hpp"

#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "texwarp/core/sample_conversion.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

// The most libpng may allocate for one ancillary chunk it keeps (PLTE, tRNS, gAMA, sRGB need bytes, not MiB).
constexpr png_alloc_size_t kMaxPngChunkBytes = png_alloc_size_t{1} << 20;

// What libpng said, in plain arrays: libpng reports an error by longjmp back to the setjmp of png_call, over the
// frames between, where no destructor may be pending (only libpng's own frames and these callbacks lie there).
struct PngMessages {
  char error[512] = {};
  char warning[512] = {};
  int warnings = 0;
};

[[noreturn]] void on_error(png_structp png, png_const_charp text) {
  auto* messages = static_cast<PngMessages*>(png_get_error_ptr(png));
  std::snprintf(messages->error, sizeof messages->error, "%s", text ? text : "libpng stopped without saying why");
  png_longjmp(png, 1);
}

void on_warning(png_structp png, png_const_charp text) {
  auto* messages = static_cast<PngMessages*>(png_get_error_ptr(png));
  if (messages->warnings++ == 0) std::snprintf(messages->warning, sizeof messages->warning, "%s", text ? text : "");
}

// Runs `body`, libpng calls on values that need no destructor only, with libpng's error return point set: false
// when libpng reported an error (its text in PngMessages::error).
template <typename Body>
bool png_call(png_structp png, Body&& body) {
  if (setjmp(png_jmpbuf(png))) return false;  // NOLINT(cert-err52-cpp): the C library's own error protocol
  body();
  return true;
}

void read_bytes(png_structp png, png_bytep data, std::size_t length) {
  auto* file = static_cast<std::FILE*>(png_get_io_ptr(png));
  if (std::fread(data, 1, length, file) != length) {
    png_error(png, std::ferror(file) ? "the file cannot be read" : "the file is cut short");
  }
}

void write_bytes(png_structp png, png_bytep data, std::size_t length) {
  auto* file = static_cast<std::FILE*>(png_get_io_ptr(png));
  if (std::fwrite(data, 1, length, file) != length) png_error(png, std::strerror(errno));
}

void flush_nothing(png_structp) {}

// libpng's read or write structures, destroyed with their owner (a constructor that throws included).
struct PngRead {
  png_structp png = nullptr;
  png_infop info = nullptr;
  PngRead() = default;
  PngRead(const PngRead&) = delete;
  PngRead& operator=(const PngRead&) = delete;
  ~PngRead() { png_destroy_read_struct(&png, &info, nullptr); }
};
struct PngWrite {
  png_structp png = nullptr;
  png_infop info = nullptr;
  PngWrite() = default;
  PngWrite(const PngWrite&) = delete;
  PngWrite& operator=(const PngWrite&) = delete;
  ~PngWrite() { png_destroy_write_struct(&png, &info); }
};

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

class PngReader {
 public:
  PngReader(const std::string& path, const ImageLimits& limits) : path_(path) {
    file_.reset(std::fopen(path.c_str(), "rb"));
    if (!file_) throw InputError(InputLocation::file(path), std::string("cannot open: ") + std::strerror(errno));
    unsigned char signature[8];
    if (std::fread(signature, 1, 8, file_.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0) {
      throw InputError(InputLocation::file(path), "cannot read as png: not a PNG file");
    }
    read_.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &messages_, on_error, on_warning);
    if (!read_.png || !(read_.info = png_create_info_struct(read_.png))) throw std::bad_alloc();
    png_ = read_.png;
    info_ = read_.info;
    png_set_read_fn(png_, file_.get(), read_bytes);
    png_set_sig_bytes(png_, 8);
    // Only IHDR, PLTE, tRNS, gAMA, sRGB and the pixels matter here: text, profiles and the rest are skipped
    // unread (a file of compressed text chunks would otherwise cost seconds of inflating per read), and no
    // ancillary chunk may make libpng allocate more than kMaxPngChunkBytes.
    static constexpr png_byte kIgnored[] = "tEXt\0zTXt\0iTXt\0iCCP\0sPLT\0eXIf\0";
    png_set_keep_unknown_chunks(png_, PNG_HANDLE_CHUNK_NEVER, kIgnored, 6);
    png_set_chunk_cache_max(png_, 128);
    png_set_chunk_malloc_max(png_, kMaxPngChunkBytes);
    if (!png_call(png_, [&] { png_read_info(png_, info_); })) refuse_header();
    ImageHeader& h = header_;
    h.width = static_cast<int>(std::min<png_uint_32>(png_get_image_width(png_, info_), 1u << 30));
    h.height = static_cast<int>(std::min<png_uint_32>(png_get_image_height(png_, info_), 1u << 30));
    check_image_size(h.width, h.height, path, limits);  // before libpng allocates its row buffers
    int srgb_intent = 0;
    double file_gamma = 0.0;
    if (png_get_sRGB(png_, info_, &srgb_intent)) {
      h.color_space = "sRGB";
    } else if (png_get_gAMA(png_, info_, &file_gamma) && file_gamma > 0.0) {
      if (std::abs(file_gamma - 1.0) < 0.01) h.color_space = "linear";
      if (std::abs(file_gamma - 1.0 / 2.2) < 0.01) h.color_space = "sRGB";
    }
    if (!png_get_sRGB(png_, info_, &srgb_intent) && png_get_gAMA(png_, info_, &file_gamma) && file_gamma > 0.0) {
      // OpenImageIO's "oiio:Gamma", rounded to hundredths; it changes only how alpha is associated.
      const auto g = static_cast<float>(1.0 / file_gamma);
      gamma_ = std::round(static_cast<float>(100.0 * g)) / 100.0f;
    }
    // OpenImageIO's transformations: palette to RGB, tRNS to alpha, 1/2/4-bit grey to 8 bits; 16 bits host order.
    if (!png_call(png_, [&] {
          png_set_expand(png_);
          if (std::endian::native == std::endian::little) png_set_swap(png_);
          passes_ = png_set_interlace_handling(png_);
          png_read_update_info(png_, info_);
        })) {
      refuse_header();
    }
    h.channels = png_get_channels(png_, info_);
    h.alpha_channel = h.channels == 2 ? 1 : h.channels == 4 ? 3 : -1;
    h.format = png_get_bit_depth(png_, info_) == 16 ? PixelFormat::kUint16 : PixelFormat::kUint8;
    check_image_channels(h.channels, path, limits);
    if (passes_ > 1) {
      h.decoder_whole_image_bytes = static_cast<std::uint64_t>(h.width) * static_cast<std::uint64_t>(h.height) *
                                    static_cast<std::uint64_t>(h.channels) *
                                    (h.format == PixelFormat::kUint16 ? 2u : 1u);
    }
    warnings_before_pixels_ = messages_.warnings;
  }
  PngReader(const PngReader&) = delete;
  PngReader& operator=(const PngReader&) = delete;
  ~PngReader() = default;

  const ImageHeader& header() const { return header_; }

  // Decodes the whole image into `image` (sized and empty), appending a band of rows at a time; CanceledError before
  // a band when `control` is cancelled.
  void read(Image& image, const RunControl& control) {
    if (header_.format == PixelFormat::kUint16) {
      read_rows<std::uint16_t>(image, control);
    } else {
      read_rows<std::uint8_t>(image, control);
    }
    if (!png_call(png_, [&] { png_read_end(png_, nullptr); })) refuse_pixels(messages_.error);
    check_warnings();
  }

 private:
  [[noreturn]] void refuse_header() const {
    throw InputError(InputLocation::file(path_), std::string("cannot read as png: ") + messages_.error);
  }
  [[noreturn]] void refuse_pixels(const char* why) const {
    throw InputError(InputLocation::file(path_), std::string("is truncated or corrupt: ") + why);
  }
  // libpng only warns about some damage to pixel data (extra compressed data): once pixels are decoded, a
  // warning is an error. Warnings about the chunks before them (an odd colour profile) concern metadata texwarp
  // does not use, and were ignored before. (A palette index beyond the palette draws no warning from libpng
  // 1.6: libpng pads the palette to 256 black entries, so such a pixel decodes as black.)
  void check_warnings() const {
    if (messages_.warnings > warnings_before_pixels_) refuse_pixels(messages_.warning);
  }

  template <typename T>
  void read_rows(Image& image, const RunControl& control) {
    const int width = header_.width;
    const int height = header_.height;
    const int channels = header_.channels;
    const std::size_t row_values = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
    const std::size_t band_rows = std::max<std::size_t>(1, kImageDecodeChunkBytes / (row_values * sizeof(float)));
    const auto finish_row = [&](T* row, float* out) {
      if (header_.alpha_channel >= 0)
        associate_alpha(row, static_cast<std::size_t>(width), channels, header_.alpha_channel, gamma_);
      samples_to_float(row, row_values, out);
    };
    if (passes_ > 1) {
      // Interlaced: every pass revisits every row, so the file's samples are held whole (pages committed as
      // passes fill them), then converted a band at a time.
      const std::size_t row_bytes = row_values * sizeof(T);
      std::unique_ptr<T[]> native;
      try {
        native = std::make_unique_for_overwrite<T[]>(row_values * static_cast<std::size_t>(height));
      } catch (const std::bad_alloc&) {
        throw InputError(InputLocation::file(path_), "not enough memory to decode this interlaced " +
                                                         std::to_string(width) + "×" + std::to_string(height) +
                                                         " image");
      }
      T* const rows = native.get();
      const int passes = passes_;
      // The passes are most of the decode: checked every row, leaving the C frames of libpng by returning (an
      // exception must not cross them), then thrown.
      bool canceled = false;
      if (!png_call(png_, [&] {
            for (int pass = 0; pass < passes; ++pass) {
              for (int y = 0; y < height; ++y) {
                if (control.canceled()) {
                  canceled = true;
                  return;
                }
                png_read_row(png_, reinterpret_cast<png_bytep>(rows) + static_cast<std::size_t>(y) * row_bytes,
                             nullptr);
              }
            }
          })) {
        refuse_pixels(messages_.error);
      }
      if (canceled) throw CanceledError();
      check_warnings();
      for (std::size_t y = 0; y < static_cast<std::size_t>(height); y += band_rows) {
        if (control.canceled()) throw CanceledError();
        const std::size_t end = std::min<std::size_t>(height, y + band_rows);
        const std::size_t done = image.pixels.size();
        image.pixels.resize(done + row_values * (end - y));
        for (std::size_t r = y; r < end; ++r) {
          finish_row(rows + r * row_values, image.pixels.data() + r * row_values);
        }
      }
      return;
    }
    std::vector<T> row(row_values);
    T* const row_data = row.data();
    for (std::size_t y = 0; y < static_cast<std::size_t>(height); y += band_rows) {
      if (control.canceled()) throw CanceledError();
      const std::size_t end = std::min<std::size_t>(height, y + band_rows);
      const std::size_t done = image.pixels.size();
      image.pixels.resize(done + row_values * (end - y));
      for (std::size_t r = y; r < end; ++r) {
        if (!png_call(png_, [&] { png_read_row(png_, reinterpret_cast<png_bytep>(row_data), nullptr); })) {
          refuse_pixels(messages_.error);
        }
        check_warnings();
        finish_row(row_data, image.pixels.data() + r * row_values);
      }
    }
  }

  std::string path_;
  PngMessages messages_;  // before read_: libpng holds its address until it is destroyed
  File file_;
  PngRead read_;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
  ImageHeader header_;
  float gamma_ = 1.0f;
  int passes_ = 1;
  int warnings_before_pixels_ = 0;
};

template <typename T>
void write_rows(png_structp png, const Image& image, int alpha) {
  const std::size_t row_values = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.channels);
  std::vector<T> row(row_values);
  for (int y = 0; y < image.height; ++y) {
    const float* in = image.pixels.data() + static_cast<std::size_t>(y) * row_values;
    T* out = row.data();
    for (std::size_t i = 0; i < row_values; ++i) out[i] = quantise<T>(in[i]);
    if (alpha >= 0) unassociate_alpha(out, static_cast<std::size_t>(image.width), image.channels, alpha);
    if (!png_call(png, [&] { png_write_row(png, reinterpret_cast<png_const_bytep>(out)); })) return;
  }
}

}  // namespace

ImageHeader read_png_header(const std::string& path, const ImageLimits& limits) {
  return PngReader(path, limits).header();
}

Image read_png(const std::string& path, const ImageLimits& limits, ImageHeader* header, const RunControl& control) {
  PngReader reader(path, limits);
  const ImageHeader& h = reader.header();
  Image image = reserve_image(h, path);
  reader.read(image, control);
  if (header) *header = h;
  return image;
}

PixelFormat write_png(const std::string& file, const std::string& name, const Image& image, PixelFormat format,
                      int compression_level) {
  int color_type = PNG_COLOR_TYPE_GRAY;
  int alpha = -1;  // PNG's alpha is where its colour type puts it, whatever image.alpha_channel says (as before)
  switch (image.channels) {
    case 1:
      break;
    case 2:
      color_type = PNG_COLOR_TYPE_GRAY_ALPHA;
      alpha = 1;
      break;
    case 3:
      color_type = PNG_COLOR_TYPE_RGB;
      break;
    case 4:
      color_type = PNG_COLOR_TYPE_RGB_ALPHA;
      alpha = 3;
      break;
    default:
      throw std::runtime_error("cannot write " + name + ": PNG holds 1 to 4 channels, not " +
                               std::to_string(image.channels));
  }
  const bool sixteen = format == PixelFormat::kUint16;
  File out(std::fopen(file.c_str(), "wb"));
  if (!out) throw std::runtime_error("cannot open " + name + ": " + std::strerror(errno));
  PngMessages messages;
  PngWrite write;
  write.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &messages, on_error, on_warning);
  if (!write.png || !(write.info = png_create_info_struct(write.png))) throw std::bad_alloc();
  png_structp png = write.png;
  png_infop info = write.info;
  bool ok = png_call(png, [&] {
    png_set_write_fn(png, out.get(), write_bytes, flush_nothing);
    png_set_compression_level(png, compression_level);
    // Measured on a 1024² RGBA warp at level 1 (medians of 12): the Up filter with run-length matching encodes in
    // 0.082 s to 1.52 MB; no filter (OpenImageIO's setting) 0.138 s, 2.46 MB; Paeth 0.096 s, 1.47 MB; Sub 0.093 s,
    // 1.66 MB; libpng's adaptive choice (Debian's OpenImageIO) 1.52 MB, slower still. Levels ≥ 2 keep zlib's
    // default matching (run-length matching would ignore the level).
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    if (compression_level <= 1) png_set_compression_strategy(png, Z_RLE);
    png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height),
                 sixteen ? 16 : 8, color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (sixteen && std::endian::native == std::endian::little) png_set_swap(png);
  });
  if (ok) {
    if (sixteen) {
      write_rows<std::uint16_t>(png, image, alpha);
    } else {
      write_rows<std::uint8_t>(png, image, alpha);
    }
    ok = messages.error[0] == '\0' && png_call(png, [&] { png_write_end(png, nullptr); });
  }
  const bool closed = std::fclose(out.release()) == 0;
  if (!ok) throw std::runtime_error("cannot write " + name + ": " + messages.error);
  if (!closed) throw std::runtime_error("cannot finish " + name + ": " + std::strerror(errno));
  return sixteen ? PixelFormat::kUint16 : PixelFormat::kUint8;
}

}  // namespace texwarp
