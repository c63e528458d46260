// libFuzzer target: a glTF mesh as texwarpd reads one (a .gltf or .glb blob or path): the GLB container, the JSON,
// tinygltf's model and every accessor read (parse_gltf_mesh), validate_mesh; for a valid disk, the file written back
// with new UVs must read back to the same triangles. InputError is the expected outcome for bad input.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/gltf_output.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace {

[[noreturn]] void finding(const char* what) {
  std::fprintf(stderr, "fuzz_mesh_gltf finding: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const bool binary = bytes.substr(0, 4) == "glTF";
  const auto where = texwarp::proto::InputLocation::file(binary ? "mesh.glb" : "mesh.gltf");
  try {
    const texwarp::mesh::GltfMesh gltf = texwarp::mesh::parse_gltf_mesh(bytes, binary, {}, where);
    if (gltf.corners.size() != 3 * gltf.mesh.faces.size()) finding("corners and faces disagree");
    texwarp::mesh::validate_mesh(gltf.mesh, {where, std::nullopt});
    const texwarp::mesh::MeshRegion region = texwarp::mesh::whole_mesh_region(gltf.mesh, where);
    const std::vector<std::array<double, 2>> uvs(region.vertices.size(), {0.25, 0.5});
    const std::string out = texwarp::mesh::textured_gltf_bytes(gltf, region, uvs, std::string("warped.png"));
    const texwarp::mesh::GltfMesh back = texwarp::mesh::parse_gltf_mesh(out, binary, {}, where);
    if (back.mesh.faces != gltf.mesh.faces) finding("the written file reads back to other triangles");
    for (std::size_t c = 0; c < back.corners.size(); ++c) {  // every region corner carries the new UV
      const auto& uv = back.texcoord0[back.corners[c]];
      if (uv[0] != 0.25 || uv[1] != 0.5) finding("a region corner lost its new UV");
    }
  } catch (const texwarp::InputError& error) {
    const std::string message = texwarp::proto::utf8_prefix(error.what(), 1024);
    if (!texwarp::proto::is_valid_utf8(message)) finding("utf8_prefix(InputError) is not valid UTF-8");
  }
  return 0;
}
