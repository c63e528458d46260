// Render-ready texture files: see texture_file.hpp.
#include "texwarp/core/texture_file.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <stdexcept>

#include "texwarp/core/atomic_file.hpp"
#include "texwarp/core/image_module.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

std::string lowercase_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

bool is_texture_path(const std::string& path) { return lowercase_extension(path) == ".tx"; }

std::string texture_color_space(const TextureEncoding& encoding) {
  return encoding.role == ImageRole::kColor ? encoding.color_space : "Raw";
}

WrittenTexture write_texture(const std::string& path, const Image& image, PixelFormat format,
                             const ImageEncoding& encoding, const std::string& color_space, ImageWriteTimes* times) {
  const std::string ext = lowercase_extension(path);
  if (ext != ".tx" && ext != ".tif" && ext != ".tiff" && ext != ".exr") {
    throw InputError(InputLocation::file(path),
                     "a render-ready texture (tiled, MIP-mapped) is a .tx, .tif, .tiff or .exr file");
  }
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * image.channels) {
    throw std::invalid_argument("write_texture: inconsistent image");
  }
  const auto start = std::chrono::steady_clock::now();
  const TexwarpImageModule& module = image_module("writing a texture (" + ext + ")", path);
  if (module.struct_size < sizeof(TexwarpImageModule) || module.write_texture == nullptr) {
    throw std::runtime_error("the image module cannot write textures");
  }
  const std::string temp = temporary_path_for(path);
  WrittenTexture out;
  try {
    TexwarpImageMessage message{};
    int stored_format = static_cast<int>(format);
    int stored_channels = image.channels;
    const int status = module.write_texture(
        temp.c_str(), image.width, image.height, image.channels, image.alpha_channel, static_cast<int>(format),
        static_cast<int>(encoding.compression), image.pixels.data(), color_space.c_str(), &stored_format,
        &stored_channels, &out.tile_width, &out.mip_levels, &message);
    if (status == TEXWARP_IMAGE_INPUT_ERROR) throw InputError(InputLocation::file(path), message.text);
    if (status != TEXWARP_IMAGE_OK) throw std::runtime_error("cannot write " + path + ": " + message.text);
    out.image = {static_cast<PixelFormat>(stored_format), stored_channels};
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(temp, ec);
    throw;
  }
  const auto encoded = std::chrono::steady_clock::now();
  publish_file(temp, path);
  if (times) {
    times->encode_s = std::chrono::duration<double>(encoded - start).count();
    times->write_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - encoded).count();
  }
  return out;
}

WrittenImage write_output_image(const std::string& path, const Image& image, PixelFormat format,
                                const ImageEncoding& encoding, bool texture, const std::string& color_space,
                                ImageWriteTimes* times) {
  if (texture || is_texture_path(path)) return write_texture(path, image, format, encoding, color_space, times).image;
  return write_image(path, image, format, encoding, times);
}

}  // namespace texwarp
