// tinygltf's implementation, compiled here (not Debian's libtinygltf.so) so that it never decodes images (no
// stb_image on untrusted bytes), never touches the file system (no FS callbacks: external URIs are refused) and
// is instrumented with the rest in sanitizer and fuzz builds. Configuration: texwarp/mesh/tiny_gltf.hpp.
#include <fstream>  // tinygltf 2.7 uses std::ofstream in its (unused) file writers even with TINYGLTF_NO_FS

#define TINYGLTF_IMPLEMENTATION
#include "texwarp/mesh/tiny_gltf.hpp"
