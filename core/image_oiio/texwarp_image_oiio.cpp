// The image module: every format but PNG read and written through OpenImageIO behind image_module_abi.h, built as
// a MODULE library that core dlopens on first need, so that a PNG warp never loads OpenImageIO's ~260 libraries.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/color.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include "texwarp/core/image_module_abi.h"
#include "texwarp/proto/output_enums.hpp"

namespace {

using texwarp::proto::Compression;
using texwarp::proto::PixelFormat;

struct Failure {
  int status;
  std::string text;
};

void say(TexwarpImageMessage* message, const std::string& text) {
  if (!message) return;
  std::snprintf(message->text, sizeof message->text, "%s", text.c_str());
}

// What a decoder said, without the file's path (it may be a server's own layout): the caller names the file.
std::string without_path(std::string text, const std::string& path) {
  for (auto at = text.find(path); !path.empty() && at != std::string::npos; at = text.find(path, at)) {
    text.replace(at, path.size(), "the file");
  }
  return text;
}

// The first line of what the decoder said (libtiff, for one, repeats itself for every strip).
std::string first_line(const std::string& text) {
  const std::string line = text.substr(0, text.find('\n'));
  return line.empty() ? "the decoder stopped without saying why" : line;
}

// Up to `bytes` bytes of `text`, cut at a UTF-8 character boundary (an extension is untrusted text).
std::string prefix(const std::string& text, std::size_t bytes) {
  if (text.size() <= bytes) return text;
  std::size_t end = bytes;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  return text.substr(0, end) + "…";
}

PixelFormat from_type(const OIIO::TypeDesc& t) {
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

OIIO::TypeDesc to_type(int format) {
  switch (static_cast<PixelFormat>(format)) {
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

// OpenImageIO's "compression" for a TIFF or EXR output (zip level 1 for both: EXR's PIZ wrote 1.1–2.8× slower on
// 2048² float and half maps).
const char* compression_name(int compression) {
  switch (static_cast<Compression>(compression)) {
    case Compression::kNone:
      return "none";
    case Compression::kSmall:
      return "zip:9";
    case Compression::kFast:
      break;
  }
  return "zip:1";
}

// The OpenImageIO format whose reader takes files with this extension (".tif", case-insensitive); empty if none.
std::string format_of_extension(const std::string& extension) {
  if (extension.size() < 2) return {};
  std::string ext = extension.substr(1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const auto& [format, extensions] : OIIO::get_extension_map()) {
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end()) return format;
  }
  return {};
}

// A texture's colour space in its ImageDescription, as maketx records its own facts there (key=value words; a name
// with spaces in double quotes): OpenImageIO 2.4's TIFF writer keeps "oiio:ColorSpace" itself only as EXIF's sRGB
// flag, and its OpenEXR reader answers "Linear" for every file. Empty for a name that cannot be written so.
constexpr std::string_view kColorSpaceKey = "oiio:ColorSpace=";

bool has_control_characters(const std::string& text) {
  return std::any_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; });
}

std::string color_space_description(const std::string& name) {
  if (name.empty() || name.find('"') != std::string::npos || has_control_characters(name)) return {};
  const bool spaced = name.find(' ') != std::string::npos;
  return std::string(kColorSpaceKey) + (spaced ? "\"" + name + "\"" : name);
}

// The colour space a description records (color_space_description), or empty (also for a name with control
// characters: another tool's text, not a record).
std::string described_color_space(const std::string& description) {
  std::size_t at = 0;
  while ((at = description.find(kColorSpaceKey, at)) != std::string::npos) {
    if (at == 0 || std::isspace(static_cast<unsigned char>(description[at - 1])) != 0) break;
    at += kColorSpaceKey.size();
  }
  if (at == std::string::npos) return {};
  const std::size_t begin = at + kColorSpaceKey.size();
  std::string name;
  if (begin < description.size() && description[begin] == '"') {
    const std::size_t end = description.find('"', begin + 1);
    if (end != std::string::npos) name = description.substr(begin + 1, end - begin - 1);
  } else {
    name = description.substr(begin, description.find_first_of(" \t\r\n\v\f", begin) - begin);
  }
  return has_control_characters(name) ? std::string() : name;
}

// The checks only OpenImageIO's spec can answer; the caller checks sizes and channels against its limits.
void check_header(const OIIO::ImageSpec& spec) {
  if (spec.depth > 1) {
    throw Failure{TEXWARP_IMAGE_INPUT_ERROR,
                  "image is a volume (" + std::to_string(spec.depth) + " slices); only 2D images are supported"};
  }
  // OpenImageIO reads deep data only as samples, not scan lines (which failed, naming an unopened file).
  if (spec.deep) {
    throw Failure{TEXWARP_IMAGE_INPUT_ERROR,
                  "image holds deep data (several samples a pixel); only flat images are supported: flatten it "
                  "first (e.g. oiiotool in.exr --flatten -o out.exr)"};
  }
}

}  // namespace

struct TexwarpImageReader {
  std::unique_ptr<OIIO::ImageInput> in;
  OIIO::ImageSpec spec;
  std::string path;
};

namespace {

// A read that failed, or that "succeeded" while the decoder reported a problem (libjpeg fills a truncated JPEG
// with grey and only warns; libtiff skips strips it cannot read), is an error: never a partly decoded image.
void check_decoded(TexwarpImageReader& reader, bool ok) {
  if (ok && !reader.in->has_error()) return;
  throw Failure{TEXWARP_IMAGE_INPUT_ERROR,
                "is truncated or corrupt: " + without_path(first_line(reader.in->geterror()), reader.path)};
}

// Runs `body`, turning what it throws into a status and a message.
template <typename Body>
int guarded(TexwarpImageMessage* message, Body&& body) {
  try {
    body();
    return TEXWARP_IMAGE_OK;
  } catch (const Failure& f) {
    say(message, f.text);
    return f.status;
  } catch (const std::bad_alloc&) {
    say(message, "not enough memory");
    return TEXWARP_IMAGE_FAILURE;
  } catch (const std::exception& e) {
    say(message, e.what());
    return TEXWARP_IMAGE_FAILURE;
  } catch (...) {
    say(message, "unknown error in the OpenImageIO module");
    return TEXWARP_IMAGE_FAILURE;
  }
}

const char* library_version() {
  static const std::string kVersion = "OpenImageIO " + std::string(OIIO_VERSION_STRING);
  return kVersion.c_str();
}

TexwarpImageReader* open_reader(const char* path_text, const char* format_text, TexwarpImageInfo* info, int* status,
                                TexwarpImageMessage* message) {
  std::unique_ptr<TexwarpImageReader> reader;
  *status = guarded(message, [&] {
    const std::string path = path_text;
    // One reader only, never OpenImageIO's fall-back through every reader it has (DICOM, video, raw camera files,
    // WebP's whole-file decode...) on untrusted bytes that the first reader refused: the reader the caller names
    // (by the file's first bytes), or the one the extension names.
    // Created by its format's name: created from a file name, OpenImageIO would let any reader claim the bytes.
    const std::string extension = std::filesystem::path(path).extension().string();
    const std::string format = *format_text ? std::string(format_text) : format_of_extension(extension);
    if (format.empty()) {
      throw Failure{TEXWARP_IMAGE_INPUT_ERROR,
                    "cannot read as an image: no image reader takes the extension " + prefix(extension, 32)};
    }
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::create(format);
    if (!in) {
      std::string why = without_path(OIIO::geterror(), path);
      throw Failure{TEXWARP_IMAGE_INPUT_ERROR, "cannot read as an image" + (why.empty() ? std::string() : ": " + why)};
    }
    OIIO::ImageSpec spec;
    if (!in->open(path, spec)) {
      std::string why = without_path(in->geterror(), path);
      throw Failure{TEXWARP_IMAGE_INPUT_ERROR,
                    "cannot read as " + std::string(in->format_name()) + (why.empty() ? std::string() : ": " + why)};
    }
    spec = in->spec();
    check_header(spec);
    const bool tiled = spec.tile_width > 0 && spec.tile_height > 0;
    info->width = spec.width;
    info->height = spec.height;
    info->channels = spec.nchannels;
    info->alpha_channel = spec.alpha_channel;
    info->format = static_cast<int>(from_type(spec.format));
    info->band_rows = tiled ? spec.tile_height : 1;  // read_tiles wants whole rows of tiles
    // OpenImageIO's own answer, unless it says nothing (a TIFF that is not sRGB) or nothing of the file (OpenEXR's
    // "Linear" for every file): then what the file records (described_color_space). A tool that converts colours
    // keeps the description as it was but updates what OpenImageIO reads, which therefore comes first.
    std::string color_space = spec.get_string_attribute("oiio:ColorSpace");
    if (color_space.empty() || (std::string_view(in->format_name()) == "openexr" && color_space == "Linear")) {
      const std::string described = described_color_space(spec.get_string_attribute("ImageDescription"));
      if (!described.empty()) color_space = described;
    }
    std::snprintf(info->color_space, sizeof info->color_space, "%s", color_space.c_str());
    reader = std::make_unique<TexwarpImageReader>(TexwarpImageReader{std::move(in), spec, path});
  });
  return *status == TEXWARP_IMAGE_OK ? reader.release() : nullptr;
}

int read_rows(TexwarpImageReader* reader, int y_begin, int y_end, float* out, TexwarpImageMessage* message) {
  return guarded(message, [&] {
    const OIIO::ImageSpec& spec = reader->spec;
    const bool tiled = spec.tile_width > 0 && spec.tile_height > 0;
    const bool ok = tiled ? reader->in->read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + y_begin, spec.y + y_end,
                                                   spec.z, spec.z + 1, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out)
                          : reader->in->read_scanlines(0, 0, spec.y + y_begin, spec.y + y_end, spec.z, 0,
                                                       spec.nchannels, OIIO::TypeDesc::FLOAT, out);
    check_decoded(*reader, ok);
  });
}

int close_reader(TexwarpImageReader* reader, TexwarpImageMessage* message) {
  const std::unique_ptr<TexwarpImageReader> owned(reader);
  return guarded(message, [&] { check_decoded(*owned, owned->in->close()); });
}

int write_image(const char* path_text, int width, int height, int channels, int alpha_channel, int format,
                int compression, const float* pixels, int* stored_format, int* stored_channels,
                TexwarpImageMessage* message) {
  return guarded(message, [&] {
    const std::string path = path_text;
    auto out = OIIO::ImageOutput::create(path);
    if (!out) {
      std::string why = without_path(OIIO::geterror(), path);
      throw Failure{TEXWARP_IMAGE_INPUT_ERROR, "cannot write this image format (is the extension right?)" +
                                                   (why.empty() ? std::string() : ": " + why)};
    }
    OIIO::ImageSpec spec(width, height, channels, to_type(format));
    spec.alpha_channel = alpha_channel;
    spec.attribute("compression", compression_name(compression));
    if (!out->open(path, spec)) throw Failure{TEXWARP_IMAGE_FAILURE, "cannot open: " + out->geterror()};
    if (!out->write_image(OIIO::TypeDesc::FLOAT, pixels)) {
      throw Failure{TEXWARP_IMAGE_FAILURE, "cannot write: " + out->geterror()};
    }
    if (!out->close()) throw Failure{TEXWARP_IMAGE_FAILURE, "cannot finish: " + out->geterror()};
    // What the file holds, from its header as a reader finds it: the writer stores its nearest where its format
    // lacks the one asked for (an EXR's uint8 is half) and may drop channels (a JPEG's alpha), without saying so.
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) throw Failure{TEXWARP_IMAGE_FAILURE, "cannot read back what was written: " + OIIO::geterror()};
    *stored_format = static_cast<int>(from_type(in->spec().format));
    *stored_channels = in->spec().nchannels;
  });
}

int write_texture(const char* path_text, int width, int height, int channels, int alpha_channel, int format,
                  int compression, const float* pixels, const char* color_space, int* stored_format,
                  int* stored_channels, int* tile_width, int* mip_levels, TexwarpImageMessage* message) {
  return guarded(message, [&] {
    const std::string path = path_text;
    std::string extension = std::filesystem::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool exr = extension == ".exr";
    if (!exr && extension != ".tx" && extension != ".tif" && extension != ".tiff") {
      throw Failure{TEXWARP_IMAGE_INPUT_ERROR, "a render-ready texture is a .tx, .tif, .tiff or .exr file"};
    }
    OIIO::ImageSpec source(width, height, channels, OIIO::TypeDesc::FLOAT);
    source.alpha_channel = alpha_channel;
    if (*color_space) source.attribute("oiio:ColorSpace", color_space);
    // The colour space in the description too (color_space_description); maketx adds its own words after it.
    const std::string description = color_space_description(color_space);
    if (!description.empty()) source.attribute("ImageDescription", description);
    const OIIO::ImageBuf image(source, const_cast<float*>(pixels));  // wraps the pixels, read only
    OIIO::ImageSpec config(to_type(format));
    config.tile_width = 64;
    config.tile_height = 64;
    config.tile_depth = 1;
    config.attribute("maketx:fileformatname", exr ? "openexr" : "tiff");
    config.attribute("compression", compression_name(compression));
    if (*color_space) config.attribute("oiio:ColorSpace", color_space);
    std::stringstream log;
    if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, image, path, config, &log)) {
      throw Failure{TEXWARP_IMAGE_FAILURE, "cannot make the texture: " + without_path(OIIO::geterror(), path)};
    }
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) throw Failure{TEXWARP_IMAGE_FAILURE, "cannot read back what was written: " + OIIO::geterror()};
    *stored_format = static_cast<int>(from_type(in->spec().format));
    *stored_channels = in->spec().nchannels;
    *tile_width = in->spec().tile_width;
    int levels = 1;
    while (in->seek_subimage(0, levels)) ++levels;
    *mip_levels = levels;
  });
}

// OpenColorIO's config as OpenImageIO holds it ($OCIO, else OpenImageIO's built-in config), made once.
const OIIO::ColorConfig& color_config() {
  static const OIIO::ColorConfig kConfig;
  return kConfig;
}

int convert_colors(const char* from, const char* to, float* pixels, size_t count, int channels, int alpha_channel,
                   TexwarpImageMessage* message) {
  return guarded(message, [&] {
    const OIIO::ColorConfig& config = color_config();
    // The scene-linear role, or OpenImageIO's "linear" where the config has no such role (its built-in one).
    const auto space = [&](const char* name) -> std::string {
      if (std::string(name) != "scene_linear") return name;
      const char* role = config.getColorSpaceNameByRole("scene_linear");
      return role && *role ? role : "linear";
    };
    OIIO::ColorProcessorHandle processor = config.createColorProcessor(space(from), space(to));
    if (!processor) {
      const std::vector<std::string> names = config.getColorSpaceNames();
      std::string list;
      for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
      const char* ocio = std::getenv("OCIO");
      const std::string where = ocio && *ocio ? std::string("the OpenColorIO config $OCIO names")
                                              : std::string("OpenImageIO's built-in config ($OCIO is not set)");
      throw Failure{TEXWARP_IMAGE_INPUT_ERROR, "no conversion from colour space \"" + prefix(from, 80) + "\" to \"" +
                                                   prefix(to, 80) + "\" in " + where +
                                                   (list.empty() ? "" : "; its spaces: " + prefix(list, 600))};
    }
    if (count == 0) return;
    // The colour channels: the first three (or one for grey) before alpha, which the conversion leaves alone.
    const int colour = channels - (alpha_channel >= 0 ? 1 : 0) >= 3 ? 3 : 1;
    const auto stride = static_cast<OIIO::stride_t>(sizeof(float)) * channels;
    processor->apply(pixels, static_cast<int>(count), 1, colour, sizeof(float), stride,
                     stride * static_cast<OIIO::stride_t>(count));
  });
}

// The config $OCIO names, read by OpenColorIO itself as OpenImageIO's ColorConfig reads it; null without $OCIO or
// when it does not load. Made once.
OCIO_NAMESPACE::ConstConfigRcPtr ocio_config() {
  static const OCIO_NAMESPACE::ConstConfigRcPtr kConfig = []() -> OCIO_NAMESPACE::ConstConfigRcPtr {
    const char* ocio = std::getenv("OCIO");
    if (!ocio || !*ocio) return nullptr;
    try {
      return OCIO_NAMESPACE::Config::CreateFromEnv();
    } catch (const std::exception&) {
      return nullptr;
    }
  }();
  return kConfig;
}

int is_data_color_space(const char* name) {
  try {
    const OCIO_NAMESPACE::ConstConfigRcPtr config = ocio_config();
    if (!config || !name) return 0;
    const OCIO_NAMESPACE::ConstColorSpaceRcPtr space = config->getColorSpace(name);
    return space && space->isData() ? 1 : 0;
  } catch (const std::exception&) {
    return 0;
  }
}

constexpr TexwarpImageModule kModule = {TEXWARP_IMAGE_MODULE_ABI_VERSION,
                                        sizeof(TexwarpImageModule),
                                        library_version,
                                        open_reader,
                                        read_rows,
                                        close_reader,
                                        write_image,
                                        convert_colors,
                                        write_texture,
                                        is_data_color_space};

}  // namespace

extern "C" __attribute__((visibility("default"))) const TexwarpImageModule* texwarp_image_module_v1(void) {
  return &kModule;
}
