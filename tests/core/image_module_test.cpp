// Where core looks for the image module (image_module.hpp) and what it loads: $TEXWARP_MODULE_DIR alone when set;
// else beside the binary (an install's ../lib/texwarp, then that folder), then the build tree, which holds it; and
// what the module records in a texture file of its colour space.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <OpenImageIO/imageio.h>

#include "test_folder.hpp"
#include "texwarp/core/image_module.hpp"
#include "texwarp/core/texture_file.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

// The test binary's own folder (core is linked into it).
fs::path binary_folder() { return fs::canonical("/proc/self/exe").parent_path(); }

TEST(ImageModule, LooksInTheEnvironmentsFolderAloneWhenItIsSet) {
  const char* before = std::getenv("TEXWARP_MODULE_DIR");
  const std::string saved = before ? before : "";
  ::setenv("TEXWARP_MODULE_DIR", "/some/where", 1);
  EXPECT_EQ(image_module_dirs(), std::vector<std::string>{"/some/where"});
  ::setenv("TEXWARP_MODULE_DIR", "", 1);  // empty: as if unset
  const std::vector<std::string> dirs = image_module_dirs();
  if (before) {
    ::setenv("TEXWARP_MODULE_DIR", saved.c_str(), 1);
  } else {
    ::unsetenv("TEXWARP_MODULE_DIR");
  }
  ASSERT_EQ(dirs.size(), 3u);
  EXPECT_EQ(dirs[0], (binary_folder().parent_path() / "lib" / "texwarp").string());
  EXPECT_EQ(dirs[1], binary_folder().string());
  EXPECT_TRUE(fs::exists(fs::path(dirs[2]) / kImageModuleFileName)) << dirs[2];
}

TEST(ImageModule, LoadsTheModuleOfThisAbiVersion) {
  if (const char* dir = std::getenv("TEXWARP_MODULE_DIR"); dir && *dir) GTEST_SKIP() << "TEXWARP_MODULE_DIR is set";
  const TexwarpImageModule& module = image_module("reading .tif", "x.tif");
  EXPECT_EQ(module.abi_version, TEXWARP_IMAGE_MODULE_ABI_VERSION);
  EXPECT_EQ(module.struct_size, sizeof(TexwarpImageModule));
  EXPECT_EQ(std::string(module.library_version()).rfind("OpenImageIO 2.", 0), 0u) << module.library_version();
  EXPECT_EQ(&image_module("writing .exr", "y.exr"), &module);  // loaded once
}

// A texture records the colour space it was given, read back as written: in a TIFF (which keeps only sRGB itself)
// and an EXR (whose float pixels OpenImageIO reads as "Linear" otherwise); a name with spaces too. A name that
// cannot be recorded is left out rather than garbled.
TEST(ImageModule, ATextureRecordsItsColourSpace) {
  const testing::TestFolder dir("module");
  Image image(8, 8, 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(i % 7) / 7.0f;
  struct Case {
    const char* file;
    PixelFormat format;
    std::string color_space;
    std::string read_back;
  };
  for (const Case& c :
       {Case{"raw.tx", PixelFormat::kUint8, "Raw", "Raw"},
        Case{"aces.tif", PixelFormat::kUint16, "ACES - ACEScg", "ACES - ACEScg"},
        Case{"raw.exr", PixelFormat::kHalf, "Raw", "Raw"}, Case{"srgb.tx", PixelFormat::kUint8, "sRGB", "sRGB"},
        Case{"quoted.tif", PixelFormat::kUint8, "a \"b\"", ""}}) {
    const std::string path = (dir.path() / c.file).string();
    const WrittenTexture written = write_texture(path, image, c.format, {}, c.color_space);
    EXPECT_EQ(written.mip_levels, 4) << c.file;
    EXPECT_EQ(read_image_header(path).color_space, c.read_back) << c.file;
  }
  // Where OpenImageIO knows the space itself it comes first: a tool that converts colours keeps the description as
  // it was (an sRGB TIFF described as linear is sRGB); an OpenEXR's "Linear" says nothing and a TIFF that is not
  // sRGB says nothing, so there the description decides, its name ending at any white space.
  struct Written {
    const char* file;
    const char* oiio_color_space;
    const char* description;
    std::string read_back;
  };
  for (const Written& w : {Written{"converted.tif", "sRGB", "oiio:ColorSpace=linear", "sRGB"},
                           Written{"described.exr", "", "oiio:ColorSpace=sRGB oiio:SHA-1=0", "sRGB"},
                           Written{"lines.tif", "", "made by hand\noiio:ColorSpace=Raw\nmore", "Raw"},
                           Written{"word.tif", "", "xoiio:ColorSpace=Raw", ""}}) {
    const std::string path = (dir.path() / w.file).string();
    OIIO::ImageSpec spec(8, 8, 3, OIIO::TypeDesc::HALF);
    if (*w.oiio_color_space) spec.attribute("oiio:ColorSpace", w.oiio_color_space);
    spec.attribute("ImageDescription", w.description);
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec)) << w.file;
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()));
    ASSERT_TRUE(out->close());
    EXPECT_EQ(read_image_header(path).color_space, w.read_back) << w.file;
  }
}

}  // namespace
}  // namespace texwarp
