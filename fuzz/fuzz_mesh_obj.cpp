// libFuzzer target: a mesh file as texwarpd reads one (mesh blob, `mesh.source.obj`, inline JSON mesh): OBJ text
// through tinyobjloader (or, for input starting with '{', the JSON mesh form), then validate_mesh and, for a
// valid mesh, its topology and whole-mesh region. InputError is the expected outcome for bad input.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/mesh_topology.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace {

[[noreturn]] void finding(const char* what, std::string_view text) {
  std::fprintf(stderr, "fuzz_mesh_obj finding: %s\n%.*s\n", what, static_cast<int>(text.size()), text.data());
  std::abort();
}

texwarp::mesh::TriangleMesh read_mesh(std::string_view text, texwarp::mesh::MeshSource& source) {
  if (!text.empty() && text.front() == '{') {
    source = {texwarp::proto::InputLocation::file("mesh.json"), texwarp::proto::JsonPath{}};
    return texwarp::mesh::mesh_from_spec(
        texwarp::proto::decode_mesh_data(texwarp::proto::parse_json(text, source.where.file_name())));
  }
  source = {texwarp::proto::InputLocation::file("mesh.obj"), std::nullopt};
  return texwarp::mesh::parse_obj_mesh(text, source.where);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    texwarp::mesh::MeshSource source;
    const texwarp::mesh::TriangleMesh mesh = read_mesh(text, source);
    texwarp::mesh::validate_mesh(mesh, source);
    const texwarp::mesh::MeshTopology topology = texwarp::mesh::analyse_topology(mesh);
    if (topology.neighbour.size() != mesh.faces.size()) finding("topology has a face count of its own", text);
    const texwarp::mesh::MeshRegion region = texwarp::mesh::whole_mesh_region(mesh, source.where);
    if (region.face_count() != mesh.face_count()) finding("the whole-mesh region lost faces", text);
    if (region.boundary.size() < 3) finding("a disk region with a boundary of fewer than 3 vertices", text);
  } catch (const texwarp::InputError& error) {
    const std::string message = texwarp::proto::utf8_prefix(error.what(), 1024);
    if (!texwarp::proto::is_valid_utf8(message)) finding("utf8_prefix(InputError) is not valid UTF-8", message);
  }
  return 0;
}
