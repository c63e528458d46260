// The libpng path (png_codec.hpp) held against OpenImageIO itself, which read and wrote PNG before: a corpus of
// PNGs of every kind (grey, grey+alpha, palette with and without tRNS, RGB, RGBA; 1 to 16 bits; interlaced; tRNS on
// grey and RGB; gAMA and sRGB; odd sizes, 1×1), written here with libpng, decodes to the same floats bit for bit;
// files texwarp writes decode (by OpenImageIO) to the same values as the files OpenImageIO wrote from the same image.
#include <png.h>

#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "test_folder.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

struct Random {
  std::uint32_t state;
  std::uint32_t next() {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  }
};

// A PNG file as libpng writes it from raw rows: what a user's tools may hand texwarp.
struct PngKind {
  int color_type;
  int bit_depth;
  bool interlaced = false;
  bool trns = false;   // tRNS: a grey or RGB value that occurs, or alphas for half the palette
  double gamma = 0.0;  // a gAMA chunk when > 0
  bool srgb = false;   // an sRGB chunk
  std::string name() const {
    return "type" + std::to_string(color_type) + "-" + std::to_string(bit_depth) + "bit" +
           (interlaced ? "-adam7" : "") + (trns ? "-trns" : "") + (gamma > 0 ? "-gama" : "") + (srgb ? "-srgb" : "");
  }
};

int samples_per_pixel(int color_type) {
  switch (color_type) {
    case PNG_COLOR_TYPE_GRAY_ALPHA:
      return 2;
    case PNG_COLOR_TYPE_RGB:
      return 3;
    case PNG_COLOR_TYPE_RGB_ALPHA:
      return 4;
    default:
      return 1;
  }
}

// The libpng calls, in a frame of plain values only (libpng's errors longjmp to its setjmp).
bool libpng_write(png_structp png, png_infop info, std::FILE* file, const PngKind& kind, int width, int height,
                  png_bytep* rows, png_colorp palette, int palette_size, png_bytep palette_alpha, int alphas,
                  png_color_16p trns_value) {
  if (setjmp(png_jmpbuf(png))) return false;  // NOLINT(cert-err52-cpp): libpng's error protocol
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), kind.bit_depth,
               kind.color_type, kind.interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (kind.color_type == PNG_COLOR_TYPE_PALETTE) png_set_PLTE(png, info, palette, palette_size);
  if (kind.trns) {
    if (kind.color_type == PNG_COLOR_TYPE_PALETTE) {
      png_set_tRNS(png, info, palette_alpha, alphas, nullptr);
    } else {
      png_set_tRNS(png, info, nullptr, 0, trns_value);
    }
  }
  if (kind.srgb) png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  if (kind.gamma > 0) png_set_gAMA(png, info, kind.gamma);
  png_write_info(png, info);
  const int passes = png_set_interlace_handling(png);
  for (int pass = 0; pass < passes; ++pass) {
    for (int y = 0; y < height; ++y) png_write_row(png, rows[y]);
  }
  png_write_end(png, nullptr);
  return true;
}

void write_png_file(const std::string& path, const PngKind& kind, int width, int height, std::uint32_t seed) {
  Random random{seed};
  const std::size_t row_bytes =
      (static_cast<std::size_t>(width) * samples_per_pixel(kind.color_type) * static_cast<std::size_t>(kind.bit_depth) +
       7) /
      8;
  std::vector<std::vector<png_byte>> rows(static_cast<std::size_t>(height), std::vector<png_byte>(row_bytes));
  for (auto& row : rows) {
    for (png_byte& b : row) b = static_cast<png_byte>(random.next());
  }
  // Alpha samples of 0 and of the maximum, where association is special.
  if (kind.color_type == PNG_COLOR_TYPE_RGB_ALPHA || kind.color_type == PNG_COLOR_TYPE_GRAY_ALPHA) {
    const auto bytes = static_cast<std::size_t>(kind.bit_depth / 8);
    const std::size_t pixel = bytes * samples_per_pixel(kind.color_type);
    if (row_bytes >= 2 * pixel) {
      std::memset(rows[0].data() + pixel - bytes, 0x00, bytes);
      std::memset(rows[0].data() + 2 * pixel - bytes, 0xff, bytes);
    }
  }
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr) << path;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  std::vector<png_color> palette(std::size_t{1} << std::min(kind.bit_depth, 8));
  for (png_color& c : palette)
    c = {static_cast<png_byte>(random.next()), static_cast<png_byte>(random.next()),
         static_cast<png_byte>(random.next())};
  std::vector<png_byte> palette_alpha(palette.size() / 2 + 1);
  for (png_byte& a : palette_alpha) a = static_cast<png_byte>(random.next());
  png_color_16 trns_value{};
  // The first pixel's value (so that it occurs), read from the packed row.
  const png_byte* first = rows[0].data();
  const auto sample = [&](std::size_t k) -> png_uint_16 {
    if (kind.bit_depth == 16) return static_cast<png_uint_16>(first[2 * k] << 8 | first[2 * k + 1]);
    if (kind.bit_depth == 8) return first[k];
    return static_cast<png_uint_16>(first[0] >> (8 - kind.bit_depth));
  };
  if (kind.color_type == PNG_COLOR_TYPE_GRAY) trns_value.gray = sample(0);
  if (kind.color_type == PNG_COLOR_TYPE_RGB) {
    trns_value.red = sample(0);
    trns_value.green = sample(1);
    trns_value.blue = sample(2);
  }
  std::vector<png_bytep> row_pointers;
  row_pointers.reserve(rows.size());
  for (auto& row : rows) row_pointers.push_back(row.data());
  if (!libpng_write(png, info, file, kind, width, height, row_pointers.data(), palette.data(),
                    static_cast<int>(palette.size()), palette_alpha.data(), static_cast<int>(palette_alpha.size()),
                    &trns_value)) {
    ADD_FAILURE() << "libpng could not write " << path;
  }
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
}

struct OiioImage {
  OIIO::ImageSpec spec;
  std::vector<float> pixels;
};

OiioImage oiio_read(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error("OpenImageIO cannot open " + path + ": " + OIIO::geterror());
  OiioImage image{in->spec(), {}};
  image.pixels.resize(static_cast<std::size_t>(image.spec.width) * image.spec.height * image.spec.nchannels);
  if (!in->read_image(0, 0, 0, image.spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
    throw std::runtime_error("OpenImageIO cannot read " + path + ": " + in->geterror());
  }
  return image;
}

// The first value where two decodes differ bit for bit, or −1.
long first_difference(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::bit_cast<std::uint32_t>(a[i]) != std::bit_cast<std::uint32_t>(b[i])) return static_cast<long>(i);
  }
  return -1;
}

std::vector<PngKind> every_kind() {
  std::vector<PngKind> kinds;
  for (const bool interlaced : {false, true}) {
    for (const int depth : {1, 2, 4, 8, 16}) {
      kinds.push_back({PNG_COLOR_TYPE_GRAY, depth, interlaced});
      kinds.push_back({PNG_COLOR_TYPE_GRAY, depth, interlaced, true});
      if (depth <= 8) {
        kinds.push_back({PNG_COLOR_TYPE_PALETTE, depth, interlaced});
        kinds.push_back({PNG_COLOR_TYPE_PALETTE, depth, interlaced, true});
      }
    }
    for (const int depth : {8, 16}) {
      kinds.push_back({PNG_COLOR_TYPE_GRAY_ALPHA, depth, interlaced});
      kinds.push_back({PNG_COLOR_TYPE_RGB, depth, interlaced});
      kinds.push_back({PNG_COLOR_TYPE_RGB, depth, interlaced, true});
      kinds.push_back({PNG_COLOR_TYPE_RGB_ALPHA, depth, interlaced});
      // gAMA changes how OpenImageIO associated alpha; an sRGB chunk overrides it.
      kinds.push_back({PNG_COLOR_TYPE_RGB_ALPHA, depth, interlaced, false, 1 / 2.2});
      kinds.push_back({PNG_COLOR_TYPE_GRAY_ALPHA, depth, interlaced, false, 1 / 1.8});
      kinds.push_back({PNG_COLOR_TYPE_RGB_ALPHA, depth, interlaced, false, 1 / 2.2, true});
      kinds.push_back({PNG_COLOR_TYPE_RGB_ALPHA, depth, interlaced, false, 1.0});
    }
    kinds.push_back({PNG_COLOR_TYPE_PALETTE, 8, interlaced, true, 1 / 2.2});
    kinds.push_back({PNG_COLOR_TYPE_RGB, 8, interlaced, true, 0.5});
  }
  return kinds;
}

TEST(PngCodec, EveryKindOfPngDecodesToTheFloatsOpenImageIoGave) {
  texwarp::testing::TestFolder dir{"png"};
  int files = 0;
  std::uint32_t seed = 1;
  for (const PngKind& kind : every_kind()) {
    for (const auto& [w, h] : {std::pair{1, 1}, std::pair{2, 1}, std::pair{7, 5}, std::pair{33, 17}}) {
      const std::string path = dir / (kind.name() + "-" + std::to_string(w) + "x" + std::to_string(h) + ".png");
      write_png_file(path, kind, w, h, seed++);
      const OiioImage expected = oiio_read(path);
      ImageHeader header;
      const Image back = read_image(path, {}, &header);
      const ImageHeader only = read_image_header(path);
      ASSERT_EQ(back.width, expected.spec.width) << path;
      ASSERT_EQ(back.height, expected.spec.height) << path;
      ASSERT_EQ(back.channels, expected.spec.nchannels) << path;
      EXPECT_EQ(back.alpha_channel, expected.spec.alpha_channel) << path;
      EXPECT_EQ(header.format,
                expected.spec.format == OIIO::TypeDesc::UINT16 ? PixelFormat::kUint16 : PixelFormat::kUint8)
          << path;
      EXPECT_EQ(only.channels, header.channels) << path;
      EXPECT_EQ(only.alpha_channel, header.alpha_channel) << path;
      EXPECT_EQ(only.format, header.format) << path;
      const long at = first_difference(back.pixels, expected.pixels);
      EXPECT_EQ(at, -1) << path << ": value " << at << " is " << back.pixels[at] << ", OpenImageIO read "
                        << expected.pixels[at];
      ++files;
    }
  }
  EXPECT_GT(files, 200);
}

// A file written by OpenImageIO as write_image did before (PNG level 1), for comparison.
void oiio_write(const std::string& path, const Image& image, PixelFormat format) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out);
  const OIIO::TypeDesc type = format == PixelFormat::kUint16  ? OIIO::TypeDesc::UINT16
                              : format == PixelFormat::kUint8 ? OIIO::TypeDesc::UINT8
                              : format == PixelFormat::kHalf  ? OIIO::TypeDesc::HALF
                                                              : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
  spec.alpha_channel = image.alpha_channel;
  spec.attribute("png:compressionLevel", 1);
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data())) << out->geterror();
  ASSERT_TRUE(out->close()) << out->geterror();
}

TEST(PngCodec, WrittenFilesHoldWhatOpenImageIoWroteFromTheSameImage) {
  texwarp::testing::TestFolder dir{"png"};
  Random random{7};
  int compared = 0;
  for (int channels = 1; channels <= 4; ++channels) {
    for (const int alpha : {-1, channels - 1}) {
      for (const PixelFormat format :
           {PixelFormat::kUint8, PixelFormat::kUint16, PixelFormat::kHalf, PixelFormat::kFloat}) {
        for (const auto& [w, h] : {std::pair{1, 1}, std::pair{13, 7}, std::pair{64, 3}}) {
          Image image(w, h, channels, alpha);
          for (float& v : image.pixels) {
            const std::uint32_t r = random.next() % 1000;
            // Mostly in [0, 1], with values beyond it, exact zeros and ones, and samples on quantisation steps.
            v = r < 50    ? -0.25f
                : r < 100 ? 1.5f
                : r < 150 ? 0.0f
                : r < 200 ? 1.0f
                : r < 300 ? static_cast<float>(random.next() % 256) / 255.0f
                          : static_cast<float>(random.next() % 100001) / 100000.0f;
          }
          if (alpha >= 0) {  // associated: colour ≤ alpha
            for (std::size_t p = 0; p < image.pixels.size(); p += static_cast<std::size_t>(channels)) {
              const float a = std::clamp(image.pixels[p + static_cast<std::size_t>(alpha)], 0.0f, 1.0f);
              for (int c = 0; c < channels; ++c) {
                if (c != alpha) image.pixels[p + static_cast<std::size_t>(c)] *= a;
              }
            }
          }
          const std::string tag = std::to_string(channels) + "c-a" + std::to_string(alpha) + "-f" +
                                  std::to_string(static_cast<int>(format)) + "-" + std::to_string(w) + "x" +
                                  std::to_string(h);
          const std::string ours = dir / (tag + "-texwarp.png");
          const std::string theirs = dir / (tag + "-oiio.png");
          write_image(ours, image, format);
          oiio_write(theirs, image, format);
          const OiioImage a = oiio_read(ours);
          const OiioImage b = oiio_read(theirs);
          EXPECT_EQ(a.spec.nchannels, b.spec.nchannels) << tag;
          EXPECT_EQ(a.spec.format, b.spec.format) << tag;
          EXPECT_EQ(a.spec.alpha_channel, b.spec.alpha_channel) << tag;
          const long at = first_difference(a.pixels, b.pixels);
          EXPECT_EQ(at, -1) << tag << ": value " << at << " reads " << a.pixels[at] << ", OpenImageIO's file "
                            << b.pixels[at] << " (source " << image.pixels[at] << ")";
          // And read_image reads texwarp's own file as OpenImageIO does.
          EXPECT_EQ(first_difference(read_image(ours).pixels, a.pixels), -1) << tag;
          ++compared;
        }
      }
    }
  }
  EXPECT_EQ(compared, 96);
}

// libpng decodes an interlaced (Adam7) image whole, in its own samples, beside the float image: the header says
// how many bytes, and a job's memory estimate counts them in its decoding phase.
TEST(PngCodec, AnInterlacedPngsWholeImageIsInTheMemoryEstimate) {
  texwarp::testing::TestFolder dir{"png"};
  write_png_file(dir / "plain.png", {PNG_COLOR_TYPE_RGB_ALPHA, 16, false}, 300, 200, 5);
  write_png_file(dir / "adam7.png", {PNG_COLOR_TYPE_RGB_ALPHA, 16, true}, 300, 200, 5);
  write_png_file(dir / "adam7-grey.png", {PNG_COLOR_TYPE_GRAY, 4, true}, 300, 200, 5);
  const ImageHeader plain = read_image_header(dir / "plain.png");
  const ImageHeader adam7 = read_image_header(dir / "adam7.png");
  EXPECT_EQ(plain.decoder_whole_image_bytes, 0u);
  EXPECT_EQ(adam7.decoder_whole_image_bytes, 300u * 200 * 4 * 2);
  EXPECT_EQ(read_image_header(dir / "adam7-grey.png").decoder_whole_image_bytes, 300u * 200);  // expanded to 8 bits
  ImageWarpMemoryInput in;
  in.output_width = 16;
  in.output_height = 16;
  in.positions = PositionMethod::kPerPixel;
  in.source = plain;
  const std::uint64_t plain_peak = image_warp_memory(in).peak_bytes();
  in.source = adam7;
  const MemoryEstimate e = image_warp_memory(in);
  // Decoding is the peak for a small output: the source as float, the decoder's bands, and now the whole image.
  EXPECT_EQ(e.peak_bytes(), plain_peak + std::uint64_t{300} * 200 * 4 * 2);
  EXPECT_NE(e.describe().find("held by the decoder 480 kB"), std::string::npos) << e.describe();
}

// A decode that is no longer wanted (a command that failed meanwhile, a canceled job) stops before its next band of
// rows: plain and interlaced files alike; uncancelled, the control changes nothing.
TEST(PngCodec, ACancelledReadStopsBeforeItsNextBand) {
  texwarp::testing::TestFolder dir{"png"};
  for (const bool interlaced : {false, true}) {
    const std::string path = dir / (interlaced ? "adam7.png" : "plain.png");
    write_png_file(path, {PNG_COLOR_TYPE_RGB_ALPHA, 16, interlaced}, 300, 200, 9);
    std::atomic<bool> cancel{true};
    RunControl control;
    control.cancel = &cancel;
    EXPECT_THROW(read_image(path, {}, nullptr, control), CanceledError) << path;
    cancel = false;
    const Image read = read_image(path, {}, nullptr, control);
    EXPECT_EQ(read.pixels, read_image(path).pixels) << path;
    EXPECT_EQ(read.width, 300);
  }
}

TEST(PngCodec, ADamagedPngIsAnInputErrorNamingTheFile) {
  texwarp::testing::TestFolder dir{"png"};
  Image image(40, 30, 3);
  Random random{3};
  for (float& v : image.pixels) v = static_cast<float>(random.next() % 256) / 255.0f;
  write_image(dir / "ok.png", image, PixelFormat::kUint8);
  std::FILE* f = std::fopen((dir / "ok.png").c_str(), "rb");
  std::string bytes(static_cast<std::size_t>(fs::file_size(dir / "ok.png")), '\0');
  ASSERT_EQ(std::fread(bytes.data(), 1, bytes.size(), f), bytes.size());
  std::fclose(f);
  const auto expect_refused = [&](const std::string& name, const std::string& content, const std::string& why) {
    std::FILE* out = std::fopen((dir / name).c_str(), "wb");
    std::fwrite(content.data(), 1, content.size(), out);
    std::fclose(out);
    try {
      read_image(dir / name);
      ADD_FAILURE() << name << " was read";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().str(), dir / name);
      EXPECT_NE(e.detail().find(why), std::string::npos) << name << ": " << e.detail();
    }
  };
  // A pixel byte flipped inside the IDAT chunk (its CRC no longer matches).
  std::string flipped = bytes;
  flipped[bytes.size() - 30] = static_cast<char>(flipped[bytes.size() - 30] ^ 0x5a);
  expect_refused("flipped.png", flipped, "is truncated or corrupt: ");
  // Found when the header is read (before a warp is spent on the file), naming the chunk and its place.
  try {
    read_image_header(dir / "flipped.png");
    ADD_FAILURE() << "flipped.png's header was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), dir / "flipped.png");
    EXPECT_NE(e.detail().find("is truncated or corrupt: the IDAT chunk at byte 33 fails its CRC check"),
              std::string::npos)
        << e.detail();
  }
  // Cut inside the pixel data, and cut after it (no IEND).
  expect_refused("cut.png", bytes.substr(0, bytes.size() / 2), "is truncated or corrupt: ");
  expect_refused("no-end.png", bytes.substr(0, bytes.size() - 12), "is truncated or corrupt: ");
  // A broken header.
  std::string header = bytes;
  header[16] = '\x7f';  // width's high byte: the IHDR CRC fails
  expect_refused("header.png", header, "cannot read as png: ");
  expect_refused("short.png", bytes.substr(0, 20), "");
}

}  // namespace
}  // namespace texwarp
