// Tests of sampling, image files (8-/16-bit, float, alpha, limits, atomic writes, truncated and lying files, banded
// decoding) and the image warp, using images whose pixel values encode their own coordinates so that every output
// pixel can be checked.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <sys/resource.h>
#include <sstream>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>

#include "lying_png.hpp"
#include "process_memory.hpp"
#include "test_folder.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_buffer.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/udim_texture.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;
using testing::lying_png;

// Channel 0 = x, channel 1 = y of the pixel centre (in pixels): bilinear and Catmull–Rom sampling reproduce
// linear functions exactly, so a sample at p reads p back (away from the border).
Image coordinate_image(int w, int h) {
  Image img(w, h, 2);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      img.pixel(x, y)[0] = static_cast<float>(x + 0.5);
      img.pixel(x, y)[1] = static_cast<float>(y + 0.5);
    }
  }
  return img;
}

TEST(Sampler, ReproducesLinearFunctions) {
  const Image img = coordinate_image(40, 30);
  float out[2];
  for (const Interpolation interp : {Interpolation::kBilinear, Interpolation::kBicubic}) {
    for (const Point p : {Point(10.5, 10.5), Point(12.3, 7.9), Point(20.01, 25.77)}) {
      sample_image(img, p, interp, Border::kClamp, out);
      EXPECT_NEAR(out[0], p.real(), 1e-4);
      EXPECT_NEAR(out[1], p.imag(), 1e-4);
    }
  }
}

TEST(Sampler, BordersBehaveAsDocumented) {
  Image img(4, 1, 1);
  for (int x = 0; x < 4; ++x) img.pixel(x, 0)[0] = static_cast<float>(10 * (x + 1));  // 10 20 30 40
  float out;
  // Centre of the virtual pixel x = −1 (p = −0.5) and x = 4 (p = 4.5).
  sample_image(img, {-0.5, 0.5}, Interpolation::kBilinear, Border::kTransparent, &out);
  EXPECT_EQ(out, 0.0f);
  sample_image(img, {-0.5, 0.5}, Interpolation::kBilinear, Border::kClamp, &out);
  EXPECT_EQ(out, 10.0f);
  sample_image(img, {-0.5, 0.5}, Interpolation::kBilinear, Border::kRepeat, &out);
  EXPECT_EQ(out, 40.0f);
  sample_image(img, {4.5, 0.5}, Interpolation::kBilinear, Border::kRepeat, &out);
  EXPECT_EQ(out, 10.0f);
  // Half-way between the last pixel and the outside: half of 40 when transparent.
  sample_image(img, {4.0, 0.5}, Interpolation::kBilinear, Border::kTransparent, &out);
  EXPECT_FLOAT_EQ(out, 20.0f);
  // Non-finite positions read nothing rather than garbage.
  sample_image(img, {std::nan(""), 0.5}, Interpolation::kBicubic, Border::kClamp, &out);
  EXPECT_EQ(out, 0.0f);
}

TEST(ImageWarp, EveryOutputPixelSamplesItsInverseMappedPosition) {
  std::vector<Feature> f = {{"a", {20, 20}, {26, 18}},
                            {"b", {80, 25}, {78, 33}},
                            {"c", {40, 70}, {45, 66}},
                            {"g", {60, 50}, {57, 52}, Frame{0.0, 1.0}, Frame{0.3, 1.2}}};
  const WarpProblem problem(f, {});
  const Image src = coordinate_image(101, 87);
  CpuBackend cpu;
  ImageWarpOptions options;
  options.border = Border::kClamp;
  options.exact = true;
  options.filter = SamplingFilter::kPoint;  // the sample at the position itself (footprints: footprint_filter_test)
  const Image out = warp_image(cpu, problem, src, options);
  ASSERT_EQ(out.width, 101);
  ASSERT_EQ(out.height, 87);
  ASSERT_EQ(out.channels, 2);
  const auto positions = cpu.inverse_map_grid(problem, 101, 87, {});
  int checked = 0;
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const Point p = positions[static_cast<std::size_t>(y) * out.width + x];
      if (p.real() < 1 || p.imag() < 1 || p.real() > 100 || p.imag() > 86) continue;  // clamped near the border
      ASSERT_NEAR(out.pixel(x, y)[0], p.real(), 2e-4);
      ASSERT_NEAR(out.pixel(x, y)[1], p.imag(), 2e-4);
      ++checked;
    }
  }
  EXPECT_GT(checked, 6000);  // of 8787: all but those mapped near or beyond the border
}

TEST(ImageWarp, TransparentBorderAddsCoverageAlpha) {
  const WarpProblem problem({{"t", {10, 10}, {30, 10}}}, [] {
    WarpOptions o;
    o.prealign = Prealign::kNone;
    return o;
  }());
  Image src(40, 20, 3);
  std::fill(src.pixels.begin(), src.pixels.end(), 0.5f);
  CpuBackend cpu;
  const Image out = warp_image(cpu, problem, src, {});
  ASSERT_EQ(out.channels, 4);
  EXPECT_EQ(out.alpha_channel, 3);
  // Shifted right by 20 px: the left 20 columns come from outside the source.
  EXPECT_EQ(out.pixel(5, 10)[3], 0.0f);
  EXPECT_EQ(out.pixel(5, 10)[0], 0.0f);
  EXPECT_FLOAT_EQ(out.pixel(30, 10)[3], 1.0f);
  EXPECT_FLOAT_EQ(out.pixel(30, 10)[1], 0.5f);
}

TEST(ImageWarp, OutputSizeIsTheCallersChoice) {
  const WarpProblem problem({}, {});
  CpuBackend cpu;
  ImageWarpOptions options;
  options.width = 13;
  options.height = 7;
  options.border = Border::kClamp;
  const Image out = warp_image(cpu, problem, coordinate_image(30, 30), options);
  EXPECT_EQ(out.width, 13);
  EXPECT_EQ(out.height, 7);
  EXPECT_FLOAT_EQ(out.pixel(12, 6)[0], 12.5f);  // identity: same coordinates, cropped
}

// blank_image is the constructor's image (a warp's output starts from it), below and above the size given huge
// pages; reserve_pixels commits nothing: the buffer is reserved, empty.
TEST(ImageBuffer, BlankImageIsTheConstructorsImage) {
  for (const auto& [w, h, c, alpha] : {std::array{13, 7, 3, -1}, std::array{2048, 1100, 2, 1}}) {
    const Image blank = blank_image(w, h, c, alpha);
    const Image made(w, h, c, alpha);
    EXPECT_EQ(blank.width, w);
    EXPECT_EQ(blank.height, h);
    EXPECT_EQ(blank.channels, c);
    EXPECT_EQ(blank.alpha_channel, alpha);
    ASSERT_EQ(blank.pixels.size(), made.pixels.size());
    EXPECT_EQ(blank.pixels, made.pixels);  // all 0.0f
    EXPECT_EQ(blank.pixels.capacity(), blank.pixels.size());
  }
  EXPECT_GE(std::size_t{2048} * 1100 * 2 * sizeof(float), kHugePageBufferBytes);
  Image reserved;
  reserve_pixels(reserved, std::size_t{4} << 20);
  EXPECT_TRUE(reserved.pixels.empty());
  EXPECT_GE(reserved.pixels.capacity(), std::size_t{4} << 20);
}

// huge_page_vector is a vector of zeros of that size; a large one is backed by transparent huge pages once written,
// where the system has them (its mapping's AnonHugePages in /proc/self/smaps). Where THP is "madvise" (this machine's
// setting) the advice alone makes the difference.
TEST(ImageBuffer, LargePerPixelBuffersAreBackedByHugePages) {
  for (const std::size_t n : {std::size_t{1000}, std::size_t{4} << 20}) {
    const std::vector<Point> v = huge_page_vector<Point>(n);
    ASSERT_EQ(v.size(), n);
    EXPECT_EQ(v.capacity(), n);
    EXPECT_TRUE(std::all_of(v.begin(), v.end(), [](Point p) { return p == Point(0.0); }));
  }
  // Where this process can have no 2 MiB pages the advice cannot show: THP off for the system or for 2 MiB pages
  // (kernels with several sizes), or for this process (prctl PR_SET_THP_DISABLE, inherited).
  const auto first_line = [](const std::string& path) {
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);
    return line;
  };
  const std::string setting = first_line("/sys/kernel/mm/transparent_hugepage/enabled");
  const std::string pmd_size = first_line("/sys/kernel/mm/transparent_hugepage/hugepages-2048kB/enabled");
  std::ifstream status("/proc/self/status");
  bool process_off = false;
  for (std::string line; std::getline(status, line);) process_off |= line.rfind("THP_enabled:\t0", 0) == 0;
  if (setting.empty() || setting.find("[never]") != std::string::npos ||
      pmd_size.find("[never]") != std::string::npos || process_off) {
    GTEST_SKIP() << "no transparent huge pages here";
  }
  // The kernel's count of huge-page faults it could not serve (fragmented memory): then it tried, which is what the
  // advice asks, and the test cannot tell more.
  const auto fallbacks = [] {
    std::ifstream vmstat("/proc/vmstat");
    for (std::string name, value; vmstat >> name >> value;) {
      if (name == "thp_fault_fallback") return std::stoll(value);
    }
    return -1LL;
  };
  const long long fallbacks_before = fallbacks();
  std::vector<Point> grid = huge_page_vector<Point>(std::size_t{4} << 20);  // 64 MiB, a 2048² grid's map
  for (std::size_t i = 0; i < grid.size(); i += 256) grid[i] = Point(static_cast<double>(i));
  // The middle of the buffer: its first page, beside malloc's header, is not advised (a mapping of its own).
  const auto at = reinterpret_cast<std::uintptr_t>(grid.data() + grid.size() / 2);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  long huge_kib = -1;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin = 0;
    std::uintptr_t end = 0;
    char dash = 0;
    std::istringstream range(line);
    if (range >> std::hex >> begin >> dash >> end && dash == '-' && line.find(':') > line.find(' ')) {
      inside = begin <= at && at < end;
    } else if (inside && line.rfind("AnonHugePages:", 0) == 0) {
      huge_kib = std::stol(line.substr(14));
      break;
    }
  }
  ASSERT_GE(huge_kib, 0) << "no mapping holds the buffer";
  constexpr long kHalfKib = 32L * 1024;  // half of the 64 MiB
  if (huge_kib < kHalfKib && fallbacks() > fallbacks_before) GTEST_SKIP() << "no free huge pages to give";
  // Where THP is "always" every large buffer has them, advised or not.
  EXPECT_GE(huge_kib, kHalfKib) << "THP: " << setting;
}

// Cancelled, a read through the image module (TIFF) or of a UDIM canvas stops before its next band of rows, as a
// PNG's does (png_codec_test); uncancelled, the control changes nothing.
TEST(ImageIo, ACancelledReadThroughTheModuleOrOfAUdimCanvasStops) {
  texwarp::testing::TestFolder dir{"image"};
  Image img(64, 48, 3);
  for (std::size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<float>(i % 97) / 96.0f;
  write_image(dir / "a.tif", img, PixelFormat::kUint16);
  write_image(dir / "t.1001.png", img, PixelFormat::kUint8);
  write_image(dir / "t.1002.png", img, PixelFormat::kUint8);
  const UdimCanvas canvas = find_udim_tiles(dir / "t.<UDIM>.png", InputLocation::flag("--in"));
  std::atomic<bool> cancel{true};
  RunControl control;
  control.cancel = &cancel;
  EXPECT_THROW(read_image(dir / "a.tif", {}, nullptr, control), CanceledError);
  EXPECT_THROW(read_udim_canvas(canvas, Border::kClamp, {}, control), CanceledError);
  cancel = false;
  EXPECT_EQ(read_image(dir / "a.tif", {}, nullptr, control).pixels, read_image(dir / "a.tif").pixels);
  const Image whole = read_udim_canvas(canvas, Border::kClamp, {}, control);
  EXPECT_EQ(whole.width, 128);
  EXPECT_EQ(whole.pixels, read_udim_canvas(canvas, Border::kClamp).pixels);
}

TEST(ImageIo, RoundTripsEightSixteenBitAndFloat) {
  texwarp::testing::TestFolder dir{"image"};
  Image img(17, 9, 3);
  for (std::size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<float>((i * 37) % 256) / 255.0f;
  struct Case {
    std::string name;
    PixelFormat format;
    double tolerance;
  };
  for (const Case& c : {Case{"a.png", PixelFormat::kUint8, 0.5 / 255}, Case{"b.png", PixelFormat::kUint16, 0.5 / 65535},
                        Case{"c.tif", PixelFormat::kFloat, 0.0}, Case{"d.exr", PixelFormat::kHalf, 1e-3}}) {
    write_image(dir / c.name, img, c.format);
    ImageHeader header;
    const Image back = read_image(dir / c.name, {}, &header);
    EXPECT_EQ(header.format, c.format) << c.name;
    ASSERT_EQ(back.width, 17);
    ASSERT_EQ(back.channels, 3);
    for (std::size_t i = 0; i < img.pixels.size(); ++i)
      ASSERT_NEAR(back.pixels[i], img.pixels[i], c.tolerance) << c.name;
  }
  // Only the final files are left: no temporaries.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 4);
}

TEST(ImageIo, KeepsAlpha) {
  texwarp::testing::TestFolder dir{"image"};
  Image img(4, 4, 4, 3);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) {
      float* p = img.pixel(x, y);
      p[3] = static_cast<float>(x) / 3.0f;
      p[0] = p[1] = p[2] = 0.5f * p[3];  // associated
    }
  }
  write_image(dir / "a.png", img, PixelFormat::kUint16);
  const Image back = read_image(dir / "a.png");
  EXPECT_EQ(back.alpha_channel, 3);
  EXPECT_NEAR(back.pixel(3, 0)[3], 1.0f, 1e-4);
  EXPECT_NEAR(back.pixel(3, 0)[0], 0.5f, 1e-4);
  EXPECT_NEAR(back.pixel(1, 2)[0], 0.5f / 3.0f, 1e-4);
}

TEST(ImageIo, ChecksLimitsFromTheHeader) {
  texwarp::testing::TestFolder dir{"image"};
  write_image(dir / "big.png", Image(64, 32, 1), PixelFormat::kUint8);
  ImageLimits limits;
  limits.max_pixels = 1000;
  try {
    read_image(dir / "big.png", limits);
    FAIL() << "limit not enforced";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2048 pixels, more than the limit of 1000"), std::string::npos) << e.what();
  }
  limits = {};
  limits.max_dimension = 50;
  EXPECT_THROW(read_image_header(dir / "big.png", limits), InputError);
}

TEST(ImageIo, ClearErrorsForMissingAndBrokenFiles) {
  texwarp::testing::TestFolder dir{"image"};
  try {
    read_image(dir / "none.png");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("none.png: no such file"), std::string::npos);
  }
  {
    std::FILE* f = std::fopen((dir / "junk.png").c_str(), "wb");
    std::fputs("this is not a png", f);
    std::fclose(f);
  }
  EXPECT_THROW(read_image(dir / "junk.png"), InputError);
  EXPECT_THROW(write_image(dir / "x.unknownext", Image(2, 2, 1), PixelFormat::kUint8), InputError);
}

TEST(ImageIo, FailedWriteLeavesNothingBehind) {
  texwarp::testing::TestFolder dir{"image"};
  // A directory where the file should go: the final rename fails, and the temporary is removed.
  fs::create_directories(dir.path() / "taken.png" / "inside");
  EXPECT_ANY_THROW(write_image(dir / "taken.png", Image(3, 3, 1), PixelFormat::kUint8));
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 1);  // only the directory that was in the way
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_bytes(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

// Noise, so that every format's pixel data (JPEG's included) fills most of the file.
Image noise_image(int w, int h, int channels) {
  Image img(w, h, channels);
  std::uint32_t state = 12345;
  for (float& v : img.pixels) {
    state = state * 1664525u + 1013904223u;
    v = static_cast<float>(state >> 24) / 255.0f;
  }
  return img;
}

// The whole image read at once by OpenImageIO itself, as read_image did before it decoded in bands.
std::vector<float> whole_image_read(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  const OIIO::ImageSpec spec = in->spec();
  std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data())) {
    throw std::runtime_error("cannot read " + path + ": " + in->geterror());
  }
  return pixels;
}

TEST(ImageIo, TruncatedFilesOfEveryFormatAreErrorsNeverPartialImages) {
  texwarp::testing::TestFolder dir{"image"};
  const Image img = noise_image(192, 160, 3);
  for (const auto& [name, format] : {std::pair{"a.png", PixelFormat::kUint8}, std::pair{"b.jpg", PixelFormat::kUint8},
                                     std::pair{"c.tif", PixelFormat::kUint8}, std::pair{"d.exr", PixelFormat::kHalf}}) {
    write_image(dir / name, img, format);
    const std::string whole = file_bytes(dir / name);
    ASSERT_GT(whole.size(), 10000u) << name;
    EXPECT_EQ(read_image(dir / name).width, 192) << name;  // whole, it reads
    const std::string cut = std::string("cut-") + name;
    write_bytes(dir / cut, whole.substr(0, whole.size() / 2));
    try {
      read_image(dir / cut);
      ADD_FAILURE() << cut << " read as an image";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().str(), dir / cut);
      EXPECT_NE(e.detail().find("is truncated or corrupt: "), std::string::npos) << e.what();
    }
  }
}

// A 166-byte OpenEXR file whose "Software" attribute declares 1.9 GB (found by fuzz/fuzz_image_header): refused
// before OpenEXR allocates what it declares, with or without an extension.
TEST(ImageIo, AnExrHeaderThatDeclaresMoreThanTheFileHoldsIsRefusedCheaply) {
  texwarp::testing::TestFolder dir{"image"};
  const std::string reproducer = file_bytes(
      (fs::path(TEXWARP_SOURCE_DIR) / "fuzz/regressions/fuzz_image_header/exr-string-attribute-1.8GB").string());
  ASSERT_GT(reproducer.size(), 100u);
  const std::string exr = reproducer.substr(1);  // the fuzz target's first byte chose the extension
  for (const std::string name : {"bomb.exr", "bomb"}) {
    write_bytes(dir / name, exr);
    const long before = testing::process_memory_kib(0, "VmHWM");
    try {
      read_image_header(dir / name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.detail(), "not a valid OpenEXR file: header attribute \"Software\" declares 1868759150 bytes, more "
                            "than the file holds");
    }
    EXPECT_LT(testing::process_memory_kib(0, "VmHWM") - before, 50 * 1024) << name;
  }
  const Image img = noise_image(24, 16, 3);  // a valid EXR still reads
  write_image(dir / "ok.exr", img, PixelFormat::kHalf);
  EXPECT_EQ(read_image(dir / "ok.exr").width, 24);
}

// The reproducer `name` of fuzz/regressions/fuzz_image_header, without the byte that chose its extension.
std::string fuzz_regression(const std::string& name) {
  return file_bytes((fs::path(TEXWARP_SOURCE_DIR) / "fuzz/regressions/fuzz_image_header" / name).string()).substr(1);
}

// `bytes` written as `name` in `dir` and refused by read_image_header with exactly `why`, having grown the process's
// peak memory by less than 50 MB.
void expect_refused_cheaply(const texwarp::testing::TestFolder& dir, const std::string& name, const std::string& bytes,
                            const std::string& why) {
  write_bytes(dir / name, bytes);
  const long before = testing::process_memory_kib(0, "VmHWM");
  try {
    read_image_header(dir / name);
    ADD_FAILURE() << name << " was accepted; expected: " << why;
  } catch (const InputError& e) {
    EXPECT_EQ(e.detail(), why) << name;
    EXPECT_EQ(e.where().str(), dir / name);
  }
  EXPECT_LT(testing::process_memory_kib(0, "VmHWM") - before, 50 * 1024) << name;
}

// A tiled OpenEXR file of 64×48 RGB half pixels of 0.25, in tiles of `tile` × `tile`, written by OpenImageIO.
std::string tiled_exr(const std::string& path, int tile) {
  auto out = OIIO::ImageOutput::create(path);
  OIIO::ImageSpec spec(64, 48, 3, OIIO::TypeDesc::HALF);
  spec.tile_width = tile;
  spec.tile_height = tile;
  const std::vector<float> pixels(std::size_t{64} * 48 * 3, 0.25f);
  if (!out || !out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close()) {
    throw std::runtime_error("cannot write " + path);
  }
  return file_bytes(path);
}

// `exr` with the value of header attribute `name` (of `type`) replaced by the little-endian 32-bit `values`.
std::string with_exr_attribute(std::string exr, const std::string& name, const std::string& type,
                               const std::vector<std::uint32_t>& values) {
  const std::string key = name + '\0' + type + '\0';
  const std::size_t at = exr.find(key);
  if (at == std::string::npos) throw std::runtime_error("no attribute " + name);
  std::size_t value = at + key.size() + 4;  // after its size
  for (const std::uint32_t v : values) {
    for (int k = 0; k < 4; ++k) exr[value++] = static_cast<char>((v >> (8 * k)) & 0xff);
  }
  return exr;
}

// OpenEXR allocates a buffer of a whole tile, and a table of every chunk's offset, when it opens a tiled file, before
// it reads either. An 884-byte file declaring 14000×14000 tiles made it allocate 1.2 GB (fuzz_image_header); tiles
// are held to kMaxExrTileBytes, offset tables to the file that must hold them, data windows to the limits, all before
// OpenImageIO opens the file. Tiles larger than the image but within the bound still read.
TEST(ImageIo, AnExrsTilesAndChunkTableAreCheckedBeforeOpenExrAllocatesThem) {
  texwarp::testing::TestFolder dir{"image"};
  const std::string reproducer = fuzz_regression("exr-tile-of-14000x14000-1.2GB");
  const std::string exr = tiled_exr(dir / "tiled.exr", 32);
  ASSERT_EQ(reproducer.size(), 884u);
  EXPECT_EQ(read_image(dir / "tiled.exr").width, 64);
  const std::string size = std::to_string(exr.size());
  const std::pair<std::string, std::string> refused[] = {
      {reproducer,
       "OpenEXR tiles of 14000×14000 pixels are larger than texwarp reads (at most 64 MiB a tile); save the image "
       "with smaller tiles (e.g. oiiotool in.exr --tile 64 64 -o out.exr)"},
      // 2048 × 2048 × 6 bytes fit; 2048 × 5462 × 6 bytes are one more row than 64 MiB holds
      {with_exr_attribute(exr, "tiles", "tiledesc", {2048, 5462}),
       "OpenEXR tiles of 2048×5462 pixels are larger than texwarp reads (at most 64 MiB a tile); save the image "
       "with smaller tiles (e.g. oiiotool in.exr --tile 64 64 -o out.exr)"},
      {with_exr_attribute(with_exr_attribute(exr, "tiles", "tiledesc", {1, 1}), "dataWindow", "box2i",
                          {0, 0, 16383, 16383}),
       "not a valid OpenEXR file: its 16384×16384 data window takes 16384×16384 tiles, whose offsets (8 bytes each) "
       "are more than the file's " +
           size + " bytes"},
      {with_exr_attribute(with_exr_attribute(exr, "tiles", "tiledesc", {4096, 16}), "dataWindow", "box2i",
                          {0, 0, 39999, 9}),
       "image is 40000×10, larger than the limit of 32768 pixels on a side"},
      {with_exr_attribute(exr, "dataWindow", "box2i", {10, 0, 0, 9}), "image has no pixels"},
  };
  for (const auto& [bytes, why] : refused) {
    for (const std::string name : {"bomb.exr", "bomb"}) expect_refused_cheaply(dir, name, bytes, why);
  }
  tiled_exr(dir / "large-tiles.exr", 2048);
  const Image large_tiles = read_image(dir / "large-tiles.exr");  // one tile, larger than the image: it reads
  ASSERT_EQ(large_tiles.width, 64);
  EXPECT_FLOAT_EQ(large_tiles.pixel(63, 47)[2], 0.25f);
}

// Small files whose headers made a decoder allocate far more than the limits allow, inside OpenImageIO's open and
// before texwarp saw the size (hand-made, measured with /usr/bin/time): a 517-byte progressive JPEG declaring
// 65500×65500 pixels (libjpeg zeroed 12.7 GB of coefficients; fuzz_image_header hid such a frame behind bytes
// libjpeg skips), a 1 KiB RLE BMP of 32768×32768 (decoded whole: 1.1 GB), a 4 KiB TIFF of 65520×65520 tiles (51 GB
// asked, as float), a 13 KiB OpenEXR file of 600 channels on a 32768-pixel line (12 buffers of 1.2 GB asked). Each is
// refused from its header before OpenImageIO opens it, with or without an extension; a TIFF width beyond 2³¹ is named,
// not wrapped to "no pixels".
TEST(ImageIo, JpegBmpTiffAndExrHeadersAreHeldToTheLimitsBeforeTheirDecodersAllocate) {
  texwarp::testing::TestFolder dir{"image"};
  const std::pair<std::string, std::pair<std::string, std::string>> refused[] = {
      {"jpg-progressive-65500x65500-12.7GB",
       {".jpg", "image is 65500×65500, larger than the limit of 32768 pixels on a side"}},
      {"jpg-progressive-65500x65500-behind-stray-bytes-1GB",
       {".jpg", "image is 65500×65500, larger than the limit of 32768 pixels on a side"}},
      {"bmp-rle8-32768x32768-1.1GB", {".bmp", "image has 1073741824 pixels, more than the limit of 268435456"}},
      {"tif-tile-of-65520x65520-51GB",
       {".tif", "TIFF tiles of 65520×65520 pixels × 3 samples are larger than texwarp reads (at most 64 MiB a tile as "
                "float, e.g. 2048×2048 RGBA); save the image with smaller tiles (e.g. oiiotool in.tif --tile 64 64 -o "
                "out.tif)"}},
      {"tif-width-4294967295-wraps-to-no-pixels",
       {".tif", "image is 4294967295×1, larger than the limit of 32768 pixels on a side"}},
      {"exr-600-channels-of-32768-pixels-14GB", {".exr", "image has 600 channels; 1 to 4 are supported"}},
      // found by a review: a marker segment of length 0 that libjpeg steps over; TIFF sizes in signed types and a
      // tag's second copy (libtiff reads the first); a single-part tiled EXR whose "type" says scan lines
      {"jpg-app0-of-length-0-hides-65500x65500-12.7GB",
       {".jpg", "image is 65500×65500, larger than the limit of 32768 pixels on a side"}},
      {"tif-tile-tags-as-slong-65520x65520-51GB",
       {".tif", "TIFF tiles of 65520×65520 pixels × 3 samples are larger than texwarp reads (at most 64 MiB a tile as "
                "float, e.g. 2048×2048 RGBA); save the image with smaller tiles (e.g. oiiotool in.tif --tile 64 64 -o "
                "out.tif)"}},
      {"tif-duplicate-tile-tags-65520x65520-51GB",
       {".tif", "TIFF tiles of 65520×65520 pixels × 3 samples are larger than texwarp reads (at most 64 MiB a tile as "
                "float, e.g. 2048×2048 RGBA); save the image with smaller tiles (e.g. oiiotool in.tif --tile 64 64 -o "
                "out.tif)"}},
      // files whose magic only their extension's reader takes: a stray byte after a JPEG's SOI, an OS/2 "BA" bitmap
      {"jpg-stray-byte-after-soi-65500x65500-12.7GB",
       {".jpg", "image is 65500×65500, larger than the limit of 32768 pixels on a side"}},
      {"bmp-os2-ba-rle8-32768x32768-1.1GB", {".bmp", "image has 1073741824 pixels, more than the limit of 268435456"}},
      {"exr-tiled-part-typed-scanline-1.2GB",
       {".exr", "OpenEXR tiles of 14000×14000 pixels are larger than texwarp reads (at most 64 MiB a tile); save the "
                "image with smaller tiles (e.g. oiiotool in.exr --tile 64 64 -o out.exr)"}},
  };
  for (const auto& [reproducer, expected] : refused) {
    const auto& [extension, why] = expected;
    const std::string bytes = fuzz_regression(reproducer);
    ASSERT_LT(bytes.size(), 16384u) << reproducer;
    expect_refused_cheaply(dir, "bomb" + extension, bytes, why);
    expect_refused_cheaply(dir, "bomb", bytes, why);
  }
}

// A JPEG's Photoshop (APP13) segment whose IPTC block declares more than the segment holds is refused before
// OpenImageIO 2.4 reads past the segment (fuzz_image_header: 88 bytes declared in a 48-byte segment, a heap
// overflow in its decode_iptc_iim); one OpenImageIO writes itself, with an IPTC caption, reads.
TEST(ImageIo, AJpegsIptcBlockIsHeldToItsSegment) {
  texwarp::testing::TestFolder dir{"image"};
  const std::string bytes = fuzz_regression("jpg-app13-iptc-block-of-88-bytes-in-a-48-byte-segment");
  const std::string why = "is corrupt: its Photoshop (APP13) segment at byte 268 declares 88 bytes of IPTC data where "
                          "it holds 22";
  expect_refused_cheaply(dir, "iptc.jpg", bytes, why);
  expect_refused_cheaply(dir, "iptc", bytes, why);
  // A record past the block's end: the block declares its 22 bytes, its first record 300.
  std::string record = bytes;
  const std::size_t block = 268 + 4 + 24;  // the block's size, after the marker, length and IPTC header
  record[block] = 0;
  record[block + 1] = 22;
  record[block + 2] = 0x1c;
  record[block + 3] = 0x02;
  record[block + 5] = 300 >> 8;
  record[block + 6] = 300 & 0xff;
  expect_refused_cheaply(dir, "record.jpg", record,
                         "is corrupt: its Photoshop (APP13) segment at byte 268 has an IPTC record at byte 298 that "
                         "declares 300 bytes where the block holds 17");

  const fs::path good = dir / "caption.jpg";
  auto out = OIIO::ImageOutput::create("jpg");
  OIIO::ImageSpec spec(16, 8, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("IPTC:Caption", "a caption OpenImageIO keeps in an APP13 segment");
  const std::vector<unsigned char> pixels(std::size_t{16} * 8 * 3, 128);
  ASSERT_TRUE(out && out->open(good.string(), spec) && out->write_image(OIIO::TypeDesc::UINT8, pixels.data()) &&
              out->close());
  ASSERT_NE(file_bytes(good.string()).find("Photoshop 3.0"), std::string::npos);
  const Image image = read_image(good.string());
  EXPECT_EQ(image.width, 16);
  EXPECT_EQ(image.height, 8);
}

// Only the part texwarp reads (the first) is held to the limits: a multi-part OpenEXR file whose second part is
// 40000 pixels wide reads its 100×100 first part.
TEST(ImageIo, AMultiPartExrsOtherPartsAreNotHeldToTheLimits) {
  texwarp::testing::TestFolder dir{"image"};
  OIIO::ImageSpec specs[] = {OIIO::ImageSpec(100, 100, 3, OIIO::TypeDesc::HALF),
                             OIIO::ImageSpec(40000, 2, 3, OIIO::TypeDesc::HALF)};
  specs[1].full_width = specs[1].full_height = 100;  // the parts of a file share one display window
  auto out = OIIO::ImageOutput::create("parts.exr");
  ASSERT_TRUE(out);
  ASSERT_TRUE(out->open(dir / "parts.exr", 2, specs)) << out->geterror();
  for (int part = 0; part < 2; ++part) {
    if (part == 1) {
      ASSERT_TRUE(out->open(dir / "parts.exr", specs[1], OIIO::ImageOutput::AppendSubimage));
    }
    const std::vector<float> pixels(static_cast<std::size_t>(specs[part].width) * specs[part].height * 3, 0.5f);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) << out->geterror();
  }
  ASSERT_TRUE(out->close());
  const Image image = read_image(dir / "parts.exr");
  EXPECT_EQ(image.width, 100);
  EXPECT_FLOAT_EQ(image.pixel(99, 99)[0], 0.5f);
}

// A deep OpenEXR file (samples per pixel, written by OpenImageIO with none) is refused as deep when it is opened,
// not as "truncated or corrupt" when its scan lines are read.
TEST(ImageIo, ADeepExrIsRefusedForWhatItIs) {
  texwarp::testing::TestFolder dir{"image"};
  OIIO::ImageSpec spec(8, 4, 4, OIIO::TypeDesc::FLOAT);
  spec.deep = true;
  const OIIO::DeepData samples(spec);
  auto out = OIIO::ImageOutput::create("deep.exr");
  ASSERT_TRUE(out && out->open(dir / "deep.exr", spec) && out->write_deep_image(samples) && out->close());
  for (const std::string name : {"deep.exr", "deep"}) {
    if (name == "deep") fs::copy_file(dir / "deep.exr", dir / name);
    try {
      read_image(dir / name);
      ADD_FAILURE() << name << " was read";
    } catch (const InputError& e) {
      EXPECT_EQ(e.detail(), "image holds deep data (several samples a pixel); only flat images are supported: "
                            "flatten it first (e.g. oiiotool in.exr --flatten -o out.exr)");
    }
  }
}

// The bytes of a JPEG frame header's height and width (SOF0 or SOF2), replaced.
std::string with_jpeg_size(std::string jpeg, int width, int height) {
  std::size_t at = jpeg.find("\xff\xc2");
  if (at == std::string::npos) at = jpeg.find("\xff\xc0");
  if (at == std::string::npos) throw std::runtime_error("no frame header");
  const int values[] = {height, width};
  for (std::size_t k = 0; k < 2; ++k) {
    jpeg[at + 5 + 2 * k] = static_cast<char>(values[k] >> 8);
    jpeg[at + 6 + 2 * k] = static_cast<char>(values[k] & 0xff);
  }
  return jpeg;
}

// A progressive JPEG is decoded whole: libjpeg allocates and zeroes 64 coefficients of 2 bytes for every 8×8 block
// of every component when OpenImageIO opens the file. Counted from the frame header (4:2:0 here: a 64×48 image has
// 8×6 blocks of luma and 4×3 of each chroma), bounded at 256 MiB, and reported as what the decoder holds whole.
TEST(ImageIo, AProgressiveJpegsCoefficientsAreCountedAndBounded) {
  texwarp::testing::TestFolder dir{"image"};
  {
    auto out = OIIO::ImageOutput::create("jpg");
    OIIO::ImageSpec spec(64, 48, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("jpeg:progressive", 1);
    spec.attribute("jpeg:subsampling", "4:2:0");
    const std::vector<unsigned char> pixels(std::size_t{64} * 48 * 3, 200);
    ASSERT_TRUE(out && out->open(dir / "p.jpg", spec) && out->write_image(OIIO::TypeDesc::UINT8, pixels.data()) &&
                out->close());
  }
  ImageHeader header;
  const Image image = read_image(dir / "p.jpg", {}, &header);
  EXPECT_NEAR(image.pixel(63, 47)[1], 200.0f / 255, 2.0f / 255);
  EXPECT_EQ(header.decoder_whole_image_bytes, (8u * 6 + 2 * 4 * 3) * 64 * 2);
  const std::string jpeg = file_bytes(dir / "p.jpg");
  write_bytes(dir / "4096.jpg", with_jpeg_size(jpeg, 4096, 4096));  // 50 MB of coefficients: within the bound
  EXPECT_EQ(read_image_header(dir / "4096.jpg").decoder_whole_image_bytes, (512u * 512 + 2 * 256 * 256) * 128);
  expect_refused_cheaply(dir, "16384.jpg", with_jpeg_size(jpeg, 16384, 16384),
                         "JPEG image is 16384×16384 in progressive (or multi-scan) form, which is decoded whole: 805 "
                         "MB of coefficients, more than texwarp's 268 MB; convert it to a baseline JPEG, PNG or TIFF "
                         "(e.g. oiiotool in.jpg -o out.png)");
  // A baseline JPEG of the same size is read a band at a time: nothing held whole.
  write_image(dir / "b.jpg", noise_image(64, 48, 3), PixelFormat::kUint8);
  const std::string baseline = with_jpeg_size(file_bytes(dir / "b.jpg"), 16384, 16384);
  write_bytes(dir / "b16384.jpg", baseline);
  EXPECT_EQ(read_image_header(dir / "b16384.jpg").decoder_whole_image_bytes, 0u);
}

// A hand-made RLE8 BMP of 4×2 pixels, every pixel palette entry 1 (grey 0x80): OpenImageIO decodes RLE BMP files
// whole, a byte a pixel, when it opens them; the header says so for the memory estimate.
TEST(ImageIo, AnRleBmpIsCountedAsDecodedWhole) {
  texwarp::testing::TestFolder dir{"image"};
  const auto le = [](std::size_t v, int n) {
    std::string b;
    for (int k = 0; k < n; ++k) b += static_cast<char>((v >> (8 * k)) & 0xff);
    return b;
  };
  const std::string rle = std::string("\x04\x01\x00\x00\x04\x01\x00\x01", 8);  // 4 × index 1, end of line, 4 × 1, end
  std::string palette = le(0, 4) + std::string("\x80\x80\x80\x00", 4);
  std::string info = le(40, 4) + le(4, 4) + le(2, 4) + le(1, 2) + le(8, 2) + le(1, 4) + le(rle.size(), 4) +
                     le(2835, 4) + le(2835, 4) + le(2, 4) + le(0, 4);
  const std::size_t offset = 14 + 40 + palette.size();
  write_bytes(dir / "rle", "BM" + le(offset + rle.size(), 4) + le(0, 4) + le(offset, 4) + info + palette + rle);
  ImageHeader header;
  const Image image = read_image(dir / "rle", {}, &header);
  ASSERT_EQ(image.width, 4);
  ASSERT_EQ(image.height, 2);
  EXPECT_NEAR(image.pixel(3, 1)[0], 128.0f / 255, 1e-6);
  EXPECT_EQ(header.decoder_whole_image_bytes, 4u * 2);
}

// `tiff` (little-endian, as OpenImageIO writes it) with the value of `tag` in its first directory set to `value`.
std::string with_tiff_tag(std::string tiff, int tag, std::uint32_t value) {
  const auto u = [&](std::size_t at, int n) {
    std::uint32_t v = 0;
    for (int k = n - 1; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(tiff[at + k]);
    return v;
  };
  const std::size_t ifd = u(4, 4);
  for (std::uint32_t k = 0; k < u(ifd, 2); ++k) {
    const std::size_t entry = ifd + 2 + std::size_t{12} * k;
    if (static_cast<int>(u(entry, 2)) != tag) continue;
    const int bytes = u(entry + 2, 2) == 3 ? 2 : 4;
    for (int b = 0; b < bytes; ++b) tiff[entry + 8 + b] = static_cast<char>((value >> (8 * b)) & 0xff);
    return tiff;
  }
  throw std::runtime_error("no TIFF tag " + std::to_string(tag));
}

// OpenImageIO converts a TIFF tile whole to float, beside two copies in the file's samples (4096×4096 RGBA tiles of
// a 64×48 image took 390 MB): tiles are held to 64 MiB as float from the file's first directory, and a row of them
// counted in the header for the memory estimate. Files of every ordinary layout (tiled and striped, 8, 16 and 32
// bits, 1 to 4 channels) still read.
TEST(ImageIo, ATiffsTilesAreHeldTo64MibAsFloatAndOrdinaryLayoutsRead) {
  texwarp::testing::TestFolder dir{"image"};
  for (const int channels : {1, 2, 3, 4}) {
    for (const auto type : {OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT16, OIIO::TypeDesc::FLOAT}) {
      for (const int tile : {0, 16, 256}) {
        const std::string name =
            "c" + std::to_string(channels) + "-" + OIIO::TypeDesc(type).c_str() + "-" + std::to_string(tile) + ".tif";
        auto out = OIIO::ImageOutput::create(name);
        OIIO::ImageSpec spec(300, 200, channels, OIIO::TypeDesc(type));
        spec.tile_width = spec.tile_height = tile;
        std::vector<float> pixels(std::size_t{300} * 200 * static_cast<std::size_t>(channels));
        for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<float>(i % 251) / 250.0f;
        ASSERT_TRUE(out && out->open(dir / name, spec) && out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) &&
                    out->close())
            << name;
        ImageHeader header;
        const Image image = read_image(dir / name, {}, &header);
        ASSERT_EQ(image.channels, channels) << name;
        // A row of tiles in the file's samples, twice (OpenImageIO's copy, the decoder's tiles); nothing for strips.
        EXPECT_EQ(header.decoder_whole_image_bytes,
                  std::size_t{2} * 300 * static_cast<std::size_t>(std::min(tile, 200)) *
                      static_cast<std::size_t>(channels) * OIIO::TypeDesc(type).size())
            << name;
        EXPECT_NEAR(image.pixels.back(), pixels.back(), 1e-2) << name;
        EXPECT_NEAR(image.pixels[pixels.size() / 2 + 1], pixels[pixels.size() / 2 + 1], 1e-2) << name;
      }
    }
  }
  const std::string tiff = file_bytes(dir / "c3-uint8-16.tif");
  // 2048 × 2730 × 3 × 4 bytes fit in 64 MiB; one more row does not.
  write_bytes(dir / "within.tif", with_tiff_tag(with_tiff_tag(tiff, 322, 2048), 323, 2730));
  EXPECT_EQ(read_image_header(dir / "within.tif").width, 300);
  expect_refused_cheaply(dir, "beyond.tif", with_tiff_tag(with_tiff_tag(tiff, 322, 2048), 323, 2731),
                         "TIFF tiles of 2048×2731 pixels × 3 samples are larger than texwarp reads (at most 64 MiB a "
                         "tile as float, e.g. 2048×2048 RGBA); save the image with smaller tiles (e.g. oiiotool in.tif "
                         "--tile 64 64 -o out.tif)");
}

// A scan-line OpenEXR file of 64×4 RGB half pixels of 0.25 written by OpenImageIO with `compression`, and where
// its chunk-offset table starts (after the header's attributes and their terminating NUL).
std::pair<std::string, std::size_t> scanline_exr(const std::string& path, const std::string& compression) {
  auto out = OIIO::ImageOutput::create(path);
  OIIO::ImageSpec spec(64, 4, 3, OIIO::TypeDesc::HALF);
  spec.attribute("compression", compression);
  const std::vector<float> pixels(std::size_t{64} * 4 * 3, 0.25f);
  if (!out || !out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close()) {
    throw std::runtime_error("cannot write " + path);
  }
  const std::string bytes = file_bytes(path);
  std::size_t at = 8;
  while (bytes.at(at) != '\0') {  // name, type, size, value
    at = bytes.find('\0', bytes.find('\0', at) + 1) + 1;
    std::uint32_t size = 0;
    std::memcpy(&size, bytes.data() + at, 4);
    at += 4 + size;
  }
  return {bytes, at + 1};
}

// OpenEXR reads a chunk of pixels that declares no bytes, or an uncompressed chunk shorter than its pixels, without
// an error, from whatever its buffer held: a 64×1 file whose chunk declared 8 of its 384 bytes read values of up to
// 17616 where it held 0.25 (other memory of the process). Such chunks are refused before OpenEXR reads them.
TEST(ImageIo, AnExrChunkThatDeclaresFewerBytesThanItsPixelsIsRefused) {
  texwarp::testing::TestFolder dir{"image"};
  for (const std::string compression : {"none", "zip", "rle", "piz"}) {
    const auto [exr, table] = scanline_exr(dir / ("ok-" + compression + ".exr"), compression);
    const Image ok = read_image(dir / ("ok-" + compression + ".exr"));
    EXPECT_FLOAT_EQ(ok.pixel(63, 3)[1], 0.25f) << compression;
    const std::size_t chunk = compression == "none" || compression == "rle" ? 1 : 0;  // line 1, or lines 0–3
    std::uint64_t offset = 0;
    std::memcpy(&offset, exr.data() + table + 8 * chunk, 8);
    ASSERT_LT(offset + 8, exr.size()) << compression;
    const auto with_size = [&, exr = exr](std::uint32_t size) {
      std::string edited = exr;
      std::memcpy(edited.data() + offset + 4, &size, 4);  // after the chunk's first line's number
      return edited;
    };
    const std::string at = " at byte " + std::to_string(offset) + " declares ";
    expect_refused_cheaply(dir, "empty-" + compression + ".exr", with_size(0),
                           "is truncated or corrupt: its chunk of scan lines" + at + "0 bytes of pixels" +
                               (compression == "none" ? ", not the 384 its 64×1 uncompressed pixels take" : ""));
    if (compression == "none") {
      expect_refused_cheaply(dir, "short.exr", with_size(8),
                             "is truncated or corrupt: its chunk of scan lines" + at +
                                 "8 bytes of pixels, not the 384 its 64×1 uncompressed pixels take");
    }
  }
}

// 62-byte PNG files whose text, eXIf or sPLT chunk declares 1.3 GB (found by fuzz/fuzz_image_header): libpng would
// allocate the declared length before reading it. Refused by the chunk walk, naming the chunk and where it starts.
TEST(ImageIo, APngChunkThatDeclaresMoreThanTheFileHoldsIsRefusedCheaply) {
  texwarp::testing::TestFolder dir{"image"};
  for (const std::string type : {"eXIf", "iTXt", "sPLT", "tEXt", "zTXt"}) {
    const std::string reproducer = file_bytes(
        (fs::path(TEXWARP_SOURCE_DIR) / "fuzz/regressions/fuzz_image_header" / ("png-" + type + "-chunk-1.3GB"))
            .string());
    ASSERT_EQ(reproducer.size(), 62u) << type;
    for (const std::string name : {"bomb.png", "bomb"}) {
      write_bytes(dir / name, reproducer.substr(1));  // the fuzz target's first byte chose the extension
      const long before = testing::process_memory_kib(0, "VmHWM");
      try {
        read_image_header(dir / name);
        ADD_FAILURE() << type << " " << name << " was accepted";
      } catch (const InputError& e) {
        // 8 signature bytes + the 25-byte IHDR chunk; 61 - 33 - 12 = 16 bytes of the 20 written follow the header.
        EXPECT_EQ(e.detail(),
                  "is truncated or corrupt: the " + type +
                      " chunk at byte 33 declares 1296911722 bytes, more than the 16 the file holds after it");
      }
      EXPECT_LT(testing::process_memory_kib(0, "VmHWM") - before, 50 * 1024) << type << " " << name;
    }
  }
  write_image(dir / "ok.png", noise_image(24, 16, 3), PixelFormat::kUint8);  // a valid PNG still reads
  EXPECT_EQ(read_image(dir / "ok.png").width, 24);
}

// A file whose extension's reader refuses it is an error, never handed to OpenImageIO's other readers: two files
// named .exr (one with a broken header, one not EXR at all) made its WebP reader allocate 0.6 GB (fuzz_image_header).
TEST(ImageIo, AFileItsExtensionsReaderRefusesIsNotTriedByOtherReaders) {
  texwarp::testing::TestFolder dir{"image"};
  for (const auto& [name, why] :
       {std::pair<std::string, std::string>{"exr-corrupt-falls-back-to-webp-0.6GB",
                                            "not a valid OpenEXR file: a header name is longer than 31 characters"},
        {"not-exr-falls-back-to-webp-0.6GB", "cannot read as openexr: \"the file\" is not an OpenEXR file"}}) {
    const std::string reproducer =
        file_bytes((fs::path(TEXWARP_SOURCE_DIR) / "fuzz/regressions/fuzz_image_header" / name).string());
    write_bytes(dir / "bomb.exr", reproducer.substr(1));
    const long before = testing::process_memory_kib(0, "VmHWM");
    try {
      read_image_header(dir / "bomb.exr");
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.detail(), why);
    }
    EXPECT_LT(testing::process_memory_kib(0, "VmHWM") - before, 50 * 1024) << name;
  }
}

// A WebP whose canvas would take more than a decode may (OpenImageIO decodes WebP whole to open it) is refused from
// its first chunk; one beyond the limits names them.
TEST(ImageIo, AWebpCanvasIsCheckedBeforeTheWholeImageIsDecoded) {
  texwarp::testing::TestFolder dir{"image"};
  const auto vp8x = [](int width, int height) {  // RIFF header and a VP8X chunk declaring the canvas, nothing else
    std::string b = std::string("RIFF") + std::string("\x16\0\0\0", 4) + "WEBPVP8X" + std::string("\x0a\0\0\0", 4);
    b += std::string(4, '\0');
    for (const int v : {width - 1, height - 1}) {
      for (int k = 0; k < 3; ++k) b += static_cast<char>((v >> (8 * k)) & 0xff);
    }
    return b;
  };
  write_bytes(dir / "big", vp8x(12000, 9000));
  try {
    read_image_header(dir / "big");
    ADD_FAILURE() << "a 12000×9000 WebP was opened";
  } catch (const InputError& e) {
    EXPECT_EQ(e.detail(), "WebP image is 12000×9000: WebP images are read whole, and at most 64 Mpx of them; convert "
                          "larger ones to PNG, TIFF or OpenEXR");
  }
  ImageLimits small;
  small.max_dimension = 4096;
  write_bytes(dir / "wide", vp8x(5000, 10));
  try {
    read_image_header(dir / "wide", small);
    ADD_FAILURE() << "a 5000×10 WebP passed a 4096-pixel side limit";
  } catch (const InputError& e) {
    EXPECT_NE(e.detail().find("WebP image is 5000×10, beyond the limits of 4096 pixels on a side"), std::string::npos)
        << e.what();
  }
  // Within the limits, the whole RGBA canvas the decoder holds is in the header, for the memory estimate.
  write_image(dir / "small.webp", noise_image(40, 30, 3), PixelFormat::kUint8);
  fs::rename(dir / "small.webp", dir / "small");
  EXPECT_EQ(read_image_header(dir / "small").decoder_whole_image_bytes, 40u * 30 * 4);
}

// Files without an extension (uploads, inline images) are opened only by the reader their first bytes name.
TEST(ImageIo, FilesWithoutAnExtensionAreReadByTheirMagicBytesOnly) {
  texwarp::testing::TestFolder dir{"image"};
  const Image img = noise_image(24, 16, 3);
  for (const auto& [name, format] :
       {std::pair{"a.png", PixelFormat::kUint8}, std::pair{"b.jpg", PixelFormat::kUint8},
        std::pair{"c.tif", PixelFormat::kUint16}, std::pair{"d.exr", PixelFormat::kHalf}}) {
    write_image(dir / name, img, format);
    const std::string bare = std::string("bare-") + std::string(name).substr(0, 1);
    write_bytes(dir / bare, file_bytes(dir / name));
    const Image back = read_image(dir / bare);
    EXPECT_EQ(back.width, 24) << name;
    EXPECT_EQ(back.pixels, read_image(dir / name).pixels) << name;
  }
  write_bytes(dir / "pnm", "P6\n2 2\n255\n" + std::string(12, '\x7f'));  // a format OpenImageIO reads, not one we take
  try {
    read_image_header(dir / "pnm");
    ADD_FAILURE() << "a PNM upload was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.detail(), "not an image texwarp reads: expected PNG, JPEG, TIFF, OpenEXR, BMP, WebP or Radiance HDR");
  }
}

TEST(ImageIo, HeaderThatLiesFailsHavingUsedWhatTheBytesHeld) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer maps shadow memory for the whole buffer the header claims (an eighth of 4.3 GB)";
#endif
  texwarp::testing::TestFolder dir{"image"};
  const std::string bomb = lying_png(16384, 16384);  // 4.3 GB as float, in about 1 kB
  ASSERT_LT(bomb.size(), 1200u);
  write_bytes(dir / "bomb.png", bomb);
  const ImageHeader h = read_image_header(dir / "bomb.png");
  ASSERT_EQ(h.width, 16384);
  ASSERT_EQ(h.channels, 4);
  const long before = testing::process_memory_kib(0, "VmHWM");
  try {
    read_image(dir / "bomb.png");
    FAIL() << "the lying PNG read as an image";
  } catch (const InputError& e) {
    EXPECT_NE(e.detail().find("is truncated or corrupt"), std::string::npos) << e.what();
  }
  const long grown_kib = testing::process_memory_kib(0, "VmHWM") - before;
  EXPECT_LT(grown_kib, 100 * 1024) << "peak memory grew by " << grown_kib << " KiB";
}

// Without overcommit (here: an address-space limit) a header that claims more than there is memory for is an
// InputError that says so, not std::bad_alloc.
TEST(ImageIo, AHeaderBeyondTheMemoryThereIsIsAClearError) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "sanitizers reserve more address space than this test allows the process";
#endif
  texwarp::testing::TestFolder dir{"image"};
  write_bytes(dir / "bomb.png", lying_png(16384, 16384));  // 4.3 GB as float
  const std::string path = dir / "bomb.png";
  const auto read_with_2_gb = [&path] {
    const rlimit limit{rlim_t{2} << 30, rlim_t{2} << 30};
    ::setrlimit(RLIMIT_AS, &limit);
    try {
      read_image(path);
    } catch (const InputError& e) {
      std::_Exit(e.detail().rfind("not enough memory to decode this 16384×16384 image", 0) == 0 ? 0 : 3);
    } catch (...) {
      std::_Exit(2);
    }
    std::_Exit(1);
  };
  EXPECT_EXIT(read_with_2_gb(), ::testing::ExitedWithCode(0), "");
}

TEST(ImageIo, BandedDecodingReadsBitExactlyAsAWholeImageRead) {
  texwarp::testing::TestFolder dir{"image"};
  // More than one band (kImageDecodeChunkBytes of float) each, with a last band that is not full.
  const int w = 1100;
  const int h = 1030;
  ASSERT_GT(static_cast<std::size_t>(w) * h * 4 * sizeof(float), kImageDecodeChunkBytes);
  Image rgba(w, h, 4, 3);  // a pattern that compresses fast; every 16-bit value and varied alphas
  for (std::size_t i = 0; i < rgba.pixels.size(); ++i)
    rgba.pixels[i] = static_cast<float>((i * 7919) % 65536) / 65535.0f;
  write_image(dir / "a.png", rgba, PixelFormat::kUint16);  // alpha: associated on read
  write_image(dir / "b.exr", rgba, PixelFormat::kHalf);
  {  // a tiled TIFF whose last row and column of tiles are partial
    auto out = OIIO::ImageOutput::create((dir / "c.tif").string());
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::FLOAT);
    spec.tile_width = 64;
    spec.tile_height = 64;
    ASSERT_TRUE(out->open(dir / "c.tif", spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, rgba.pixels.data())) << out->geterror();
    ASSERT_TRUE(out->close());
  }
  for (const std::string name : {"a.png", "b.exr", "c.tif"}) {
    const std::vector<float> expected = whole_image_read(dir / name);
    const Image back = read_image(dir / name);
    ASSERT_EQ(back.width, w) << name;
    ASSERT_EQ(back.height, h) << name;
    ASSERT_EQ(back.pixels.size(), expected.size()) << name;
    EXPECT_EQ(std::memcmp(back.pixels.data(), expected.data(), expected.size() * sizeof(float)), 0) << name;
  }
  EXPECT_EQ(read_image_header(dir / "c.tif").format, PixelFormat::kFloat);
}

// `warp` decodes its first map while the output grid is mapped: that phase then holds the decoder's buffers too.
TEST(MemoryEstimate, ASourceDecodedWhileMappedAddsItsDecodingBuffersToTheMapping) {
  ImageWarpMemoryInput in;
  in.source.width = 1000;
  in.source.height = 500;
  in.source.channels = 3;
  const std::uint64_t held = std::uint64_t{1000} * 500 * 3;  // an interlaced 8-bit PNG's pixels
  in.source.decoder_whole_image_bytes = held;
  in.output_width = 3000;  // the lattice's phase is the peak
  in.output_height = 3000;
  const MemoryEstimate apart = image_warp_memory(in);
  ASSERT_NE(apart.describe().find("lattice nodes"), std::string::npos) << apart.describe();
  in.decoded_while_mapped = true;
  const MemoryEstimate together = image_warp_memory(in);
  ASSERT_NE(together.describe().find("lattice nodes"), std::string::npos) << together.describe();
  EXPECT_NE(together.describe().find("held by the decoder 1.5 MB"), std::string::npos) << together.describe();
  const std::uint64_t source = held * 4;
  EXPECT_EQ(together.peak_bytes() - apart.peak_bytes(),
            std::min<std::uint64_t>(source, 2 * kImageDecodeChunkBytes) + held);
}

TEST(MemoryEstimate, CountsEveryBufferOfThePeakPhase) {
  ImageWarpMemoryInput in;
  in.source.width = 1000;
  in.source.height = 500;
  in.source.channels = 3;
  in.output_width = 200;
  in.output_height = 100;
  in.positions = PositionMethod::kPerPixel;
  const MemoryEstimate e = image_warp_memory(in);
  // Resampling is the peak: source 6 MB + coverage copy 8 MB (RGB + alpha) + the MIP pyramid's third of that +
  // positions 320 kB + output 320 kB.
  EXPECT_EQ(e.peak_bytes(),
            1000u * 500 * 3 * 4 + 1000u * 500 * 4 * 4 + 1000u * 500 * 4 * 4 / 3 + 200u * 100 * 16 + 200u * 100 * 4 * 4);
  EXPECT_EQ(e.describe(),
            "about 17 MB (source with coverage alpha as float 8.0 MB, source 1000×500 RGB as float 6.0 MB, MIP pyramid "
            "(at most a third of the source) 2.7 MB, source positions of 200×100 output pixels 320 kB, output 200×100 "
            "RGBA as float 320 kB)");
  // The point filter builds no pyramid.
  ImageWarpMemoryInput point = in;
  point.pyramid = false;
  EXPECT_EQ(image_warp_memory(point).peak_bytes(),
            1000u * 500 * 3 * 4 + 1000u * 500 * 4 * 4 + 200u * 100 * 16 + 200u * 100 * 4 * 4);
  try {
    check_memory_budget(e, 10'000'000, JsonPath{"image"}, "--max-job-memory-mb");
    FAIL() << "over budget, not refused";
  } catch (const InputError& error) {
    EXPECT_EQ(error.where().str(), "$.image");
    EXPECT_NE(error.detail().find("this job needs about 17 MB"), std::string::npos) << error.what();
    EXPECT_NE(error.detail().find("the memory limit per job is 10 MB (--max-job-memory-mb)"), std::string::npos)
        << error.what();
  }
  EXPECT_NO_THROW(check_memory_budget(e, e.peak_bytes(), JsonPath{"image"}, "--max-job-memory-mb"));
  EXPECT_NO_THROW(check_memory_budget(e, 0, JsonPath{"image"}, "--max-job-memory-mb"));  // 0: no limit
  // Sizes that do not fit in 64 bits saturate rather than wrap to something small.
  in.output_width = 2'000'000'000;
  in.output_height = 2'000'000'000;
  in.positions = PositionMethod::kLattice;
  EXPECT_EQ(image_warp_memory(in).peak_bytes(), UINT64_MAX);
  EXPECT_EQ(format_bytes(999), "999 bytes");
  EXPECT_EQ(format_bytes(4'294'967'296), "4.3 GB");
  EXPECT_EQ(format_bytes(268'435'456), "268 MB");
}

// A texture set decodes each map but the first while the one before it is written: the previous map's float output
// and encoder's buffer, the positions and the next map's source with its decoding buffers are alive together.
TEST(MemoryEstimate, ATextureSetsNextDecodeOverlapsThePreviousWrite) {
  ImageWarpMemoryInput colour;
  colour.source.width = 2048;
  colour.source.height = 2048;
  colour.source.channels = 3;
  colour.transparent_border = false;
  colour.output_format = PixelFormat::kUint8;
  ImageWarpMemoryInput height = colour;
  height.source.channels = 1;
  height.output_format = PixelFormat::kFloat;
  const std::uint64_t pixels = std::uint64_t{2048} * 2048;
  const MemoryEstimate e = texture_set_overlap_memory(colour, height);
  EXPECT_EQ(e.peak_bytes(), pixels * 3 * 4 + pixels * 3 + pixels * 16 + pixels * 4 +
                                std::min<std::uint64_t>(pixels * 4, 2 * kImageDecodeChunkBytes));
  EXPECT_EQ(e.describe(),
            "about 164 MB (source positions of 2048×2048 output pixels 67 MB, previous map's output 2048×2048 RGB as "
            "float 50 MB, source 2048×2048 grey as float 17 MB, decoding buffers 17 MB, previous map's encoder's "
            "buffer 2048×2048 RGB as uint8 13 MB)");
  // Below the peak of the colour map's own warp (mapping the grid on the lattice).
  EXPECT_LT(e.peak_bytes(), image_warp_memory(colour).peak_bytes());
}

}  // namespace
}  // namespace texwarp
