// tinygltf as texwarp builds it (src/tiny_gltf_library.cpp): no image decoding or encoding, no file system. Include
// this, never <tiny_gltf.h> alone, so that every translation unit sees the same declarations.
#pragma once

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_FS
#include <tiny_gltf.h>
