// glTF input and output: every index type, welded split vertices, interleaved attributes, .gltf and .glb, the
// primitive chosen by mesh name or index; hostile files refused naming what and where; the textured file read back
// with tinygltf itself: positions and other attributes unchanged, TEXCOORD_0 = the new UVs, the material's texture.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include "gltf_accessors.hpp"
#include "texwarp/mesh/tiny_gltf.hpp"

#include "gltf_test_files.hpp"
#include "input_error_text.hpp"
#include "mesh_test_shapes.hpp"
#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/gltf_output.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_refinement.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/mesh_validation.hpp"

namespace texwarp::mesh {
namespace {

using testing::GltfFileOptions;
using testing::GltfParts;
using ::testing::HasSubstr;
using texwarp::testing::input_error_of;

const proto::InputLocation kFile = proto::InputLocation::file("model.gltf");

GltfMesh read(const std::string& bytes, bool binary, const proto::GltfSelectionSpec& selection = {}) {
  return parse_gltf_mesh(bytes, binary, selection, kFile);
}

std::string refusal(const GltfParts& parts, const proto::GltfSelectionSpec& selection = {}) {
  return input_error_of([&] { read(testing::gltf_text(parts), false, selection); });
}

// A tinygltf model of the bytes, read by tinygltf alone (images are not decoded).
tinygltf::Model load_model(const std::string& bytes, bool binary) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                           void*) { return true; },
                        nullptr);
  tinygltf::Model model;
  std::string error;
  std::string warning;
  const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                                       static_cast<unsigned int>(bytes.size()))
                         : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(),
                                                      static_cast<unsigned int>(bytes.size()), "");
  EXPECT_TRUE(ok) << error;
  return model;
}

// The grid as a welded split file reads: vertices renumbered in the order the triangles' corners first use them.
TriangleMesh in_corner_order(const TriangleMesh& mesh) {
  std::vector<int> id(mesh.vertices.size(), -1);
  TriangleMesh out;
  for (const Face& f : mesh.faces) {
    Face g{};
    for (int k = 0; k < 3; ++k) {
      if (id[f[k]] < 0) {
        id[f[k]] = out.vertex_count();
        out.vertices.push_back(mesh.vertices[f[k]]);
      }
      g[k] = id[f[k]];
    }
    out.faces.push_back(g);
  }
  return out;
}

TEST(GltfInput, EveryIndexTypeGivesTheSameMesh) {
  const TriangleMesh grid = testing::flat_grid(6, 6, 1.0, 0.2, 7);
  for (const int type : {5121, 5123, 5125, 0}) {
    for (const bool binary : {false, true}) {
      GltfFileOptions options;
      options.index_type = type;
      options.split = type == 0;  // without indices every triangle has vertices of its own
      const GltfParts parts = testing::gltf_parts(grid, options);
      const GltfMesh m = read(binary ? testing::glb_bytes(parts) : testing::gltf_text(parts), binary);
      SCOPED_TRACE("index type " + std::to_string(type) + (binary ? " glb" : " gltf"));
      const TriangleMesh expected = options.split ? in_corner_order(grid) : grid;
      ASSERT_EQ(m.mesh.vertex_count(), expected.vertex_count());
      ASSERT_EQ(m.mesh.faces, expected.faces);
      for (int v = 0; v < expected.vertex_count(); ++v) {
        EXPECT_EQ(m.mesh.vertices[v].x, static_cast<float>(expected.vertices[v].x));
        EXPECT_EQ(m.mesh.vertices[v].y, static_cast<float>(expected.vertices[v].y));
      }
      EXPECT_NO_THROW(validate_mesh(m.mesh, MeshSource{kFile, std::nullopt}));
    }
  }
}

TEST(GltfInput, SplitVerticesAreWeldedAndInterleavedAttributesRead) {
  const TriangleMesh grid = testing::flat_grid(4, 3);
  GltfFileOptions options;
  options.split = true;
  options.interleaved = true;
  const GltfMesh m = read(testing::gltf_text(testing::gltf_parts(grid, options)), false);
  const TriangleMesh expected = in_corner_order(grid);
  EXPECT_EQ(m.mesh.vertex_count(), grid.vertex_count());
  EXPECT_EQ(m.mesh.faces, expected.faces);
  ASSERT_EQ(m.mesh_vertex.size(), 3 * grid.faces.size());
  EXPECT_EQ(m.mesh_vertex[4], expected.faces[1][1]);  // glTF vertex 4: corner 1 of triangle 1
  EXPECT_EQ(m.texcoord0[4][0], static_cast<float>(grid.vertices[grid.faces[1][1]].x / 10));
}

TEST(GltfInput, ThePrimitiveIsChosenByMeshNameOrIndex) {
  const TriangleMesh small = testing::flat_grid(1, 1);
  GltfParts parts = testing::gltf_parts(small);
  // A second mesh "head" with two primitives (copies of the first mesh's).
  nlohmann::json second = parts.json["meshes"][0];
  second["name"] = "head";
  parts.json["meshes"].push_back(second);
  parts.json["meshes"][1]["primitives"].push_back(parts.json["meshes"][0]["primitives"][0]);
  proto::GltfSelectionSpec by_name;
  by_name.mesh_name = "head";
  by_name.primitive = 1;
  EXPECT_EQ(read(testing::gltf_text(parts), false, by_name).mesh_index, 1);
  EXPECT_EQ(read(testing::gltf_text(parts), false, by_name).primitive_index, 1);
  proto::GltfSelectionSpec by_index;
  by_index.mesh_index = 1;
  EXPECT_EQ(read(testing::gltf_text(parts), false, by_index).mesh_index, 1);
  by_name.mesh_name = "tail";
  EXPECT_THAT(refusal(parts, by_name), HasSubstr("no mesh named \"tail\" (its meshes: \"grid\", \"head\")"));
  by_index.mesh_index = 2;
  EXPECT_THAT(refusal(parts, by_index), HasSubstr("mesh 2 does not exist (the glTF file has 2 meshes)"));
  by_index.mesh_index = 0;
  by_index.primitive = 1;
  EXPECT_THAT(refusal(parts, by_index), HasSubstr("primitive 1 does not exist (mesh 0 (\"grid\") has 1 primitives)"));
}

TEST(GltfInput, HostileFilesAreRefusedNamingWhatAndWhere) {
  const TriangleMesh grid = testing::flat_grid(2, 2);
  const GltfParts good = testing::gltf_parts(grid);
  const int position = good.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
  const int indices = good.json["meshes"][0]["primitives"][0]["indices"];
  const auto edited = [&](auto edit) {
    GltfParts p = good;
    edit(p.json);
    return refusal(p);
  };
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["bufferViews"][0]["byteLength"] = 100000; }),
              HasSubstr("model.gltf: mesh 0 (\"grid\") primitive 0: buffer view 0 of accessor 0 (POSITION) (bytes 0 + "
                        "100000) lies outside buffer 0"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["accessors"][position]["count"] = 10; }),
              HasSubstr("accessor 0 (POSITION): 10 elements from byte 0 with stride 12 need 120 bytes"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["bufferViews"][0]["byteStride"] = 8; }),
              HasSubstr("has byteStride 8: expected 12 to 252"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["meshes"][0]["primitives"][0]["mode"] = 5; }),
              HasSubstr("primitive 0: mode 5 is not triangles (4)"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["meshes"][0]["primitives"][0]["attributes"].erase("POSITION"); }),
              HasSubstr("primitive 0: it has no POSITION attribute"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99; }),
              HasSubstr("accessor 99 (POSITION) does not exist"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["accessors"][indices]["count"] = 23; }),
              HasSubstr("23 triangle corners, not a multiple of 3"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["accessors"][position]["componentType"] = 5123; }),
              HasSubstr("POSITION must be float VEC3"));
  EXPECT_THAT(edited([&](nlohmann::json& j) {
                j["accessors"][position]["sparse"] = {{"count", 1},
                                                      {"indices", {{"bufferView", 0}, {"componentType", 5125}}},
                                                      {"values", {{"bufferView", 0}}}};
              }),
              HasSubstr("accessor 0 (POSITION) is sparse"));
  EXPECT_THAT(edited([&](nlohmann::json& j) {
                j["buffers"].push_back({{"byteLength", 4}, {"uri", "../../etc/passwd"}});
              }),
              HasSubstr("buffer 1 refers to the external file \"../../etc/passwd\", which is not read"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j["asset"]["version"] = "1.0"; }), HasSubstr("only glTF 2.x is read"));
  EXPECT_THAT(edited([&](nlohmann::json& j) { j.erase("meshes"); }), HasSubstr("the glTF file has no meshes"));
  // An index past the vertices: the last index set to 200 (u32 indices).
  GltfParts bad_index = good;
  const std::uint32_t far = 200;
  std::memcpy(bad_index.bin.data() + bad_index.bin.size() - 4, &far, 4);
  EXPECT_THAT(refusal(bad_index), HasSubstr("index 23 is 200, past the 9 POSITION elements"));
  // A non-finite position.
  GltfParts nan = good;
  const float inf = std::numeric_limits<float>::infinity();
  std::memcpy(nan.bin.data() + std::ptrdiff_t{4} * 12 + 4, &inf, 4);
  EXPECT_THAT(refusal(nan), HasSubstr("POSITION element 4 is not finite"));
  // Containers that lie.
  std::string glb = testing::glb_bytes(good);
  std::string truncated = glb.substr(0, glb.size() - 8);
  EXPECT_THAT(input_error_of([&] { read(truncated, true); }), HasSubstr("the header says"));
  std::string long_chunk = glb;
  const std::uint32_t huge = 0x7fffffff;
  std::memcpy(long_chunk.data() + 12, &huge, 4);
  EXPECT_THAT(input_error_of([&] { read(long_chunk, true); }), HasSubstr("past the end of the file"));
  EXPECT_THAT(input_error_of([&] { read("{\"asset\": ", false); }), HasSubstr("model.gltf: "));
  EXPECT_THAT(input_error_of([&] { read("[1, 2]", false); }), HasSubstr("its JSON is not an object"));
}

TEST(GltfOutput, TexcoordZeroIsTheRegionsUvsAndEverythingElseIsKept) {
  const TriangleMesh grid = testing::flat_grid(5, 4, 0.5, 0.1, 3);
  for (const bool binary : {false, true}) {
    SCOPED_TRACE(binary ? "glb" : "gltf");
    GltfFileOptions options;
    options.split = true;  // each glTF vertex belongs to one triangle: region and non-region copies differ
    const GltfParts parts = testing::gltf_parts(grid, options);
    const std::string input = binary ? testing::glb_bytes(parts) : testing::gltf_text(parts);
    const GltfMesh m = read(input, binary);
    std::vector<int> faces(20);
    std::iota(faces.begin(), faces.end(), 0);  // the grid's lower two rows of quads
    const MeshRegion region = disk_region(m.mesh, faces, kFile);
    std::vector<std::array<double, 2>> uvs;
    for (const int v : region.vertices) uvs.push_back({0.1 + 0.01 * v, 0.9 - 0.02 * v});
    const std::string out = textured_gltf_bytes(m, region, uvs, std::string("warped.png"));

    const tinygltf::Model before = load_model(input, binary);
    const tinygltf::Model after = load_model(out, binary);
    const tinygltf::Primitive& p0 = before.meshes[0].primitives[0];
    const tinygltf::Primitive& p1 = after.meshes[0].primitives[0];
    EXPECT_EQ(testing::accessor_floats(after, p1.attributes.at("POSITION")),
              testing::accessor_floats(before, p0.attributes.at("POSITION")));
    EXPECT_EQ(testing::accessor_floats(after, p1.attributes.at("NORMAL")),
              testing::accessor_floats(before, p0.attributes.at("NORMAL")));
    EXPECT_EQ(testing::accessor_floats(after, p1.attributes.at("TEXCOORD_1")),
              testing::accessor_floats(before, p0.attributes.at("TEXCOORD_1")));
    const std::vector<float> old_uv = testing::accessor_floats(before, p0.attributes.at("TEXCOORD_0"));
    const std::vector<float> new_uv = testing::accessor_floats(after, p1.attributes.at("TEXCOORD_0"));
    ASSERT_EQ(new_uv.size(), old_uv.size());
    // Corner c of triangle t is glTF vertex 3t + c (split): in the region, its vertex's UV; else as it was.
    for (int t = 0; t < grid.face_count(); ++t) {
      for (int c = 0; c < 3; ++c) {
        const std::size_t g = 3 * static_cast<std::size_t>(t) + c;
        if (t < 20) {
          const int local = region.local_vertex[m.mesh.faces[t][c]];
          EXPECT_EQ(new_uv[2 * g], static_cast<float>(uvs[local][0]));
          EXPECT_EQ(new_uv[2 * g + 1], static_cast<float>(uvs[local][1]));
        } else {
          EXPECT_EQ(new_uv[2 * g], old_uv[2 * g]);
          EXPECT_EQ(new_uv[2 * g + 1], old_uv[2 * g + 1]);
        }
      }
    }
    EXPECT_EQ(after.nodes.size(), 1u);
    EXPECT_EQ(after.nodes[0].name, "grid node");
    EXPECT_EQ(after.nodes[0].translation, (std::vector<double>{1.0, 2.0, 3.0}));
    EXPECT_EQ(after.buffers.size(), binary ? 1u : 2u);  // .glb: appended to the BIN chunk
    ASSERT_EQ(after.materials.size(), 2u);              // the primitive's own copy; material 0 unchanged
    EXPECT_EQ(after.materials[0].pbrMetallicRoughness.baseColorTexture.index, -1);
    ASSERT_EQ(p1.material, 1);
    EXPECT_EQ(after.materials[1].name, "paint (texwarp)");
    EXPECT_EQ(after.materials[1].pbrMetallicRoughness.baseColorFactor, (std::vector<double>{1, 0.5, 0.25, 1}));
    const int texture = after.materials[1].pbrMetallicRoughness.baseColorTexture.index;
    ASSERT_GE(texture, 0);
    EXPECT_EQ(after.images.at(after.textures.at(texture).source).uri, "warped.png");
    // Read back by texwarp too: the same mesh.
    EXPECT_EQ(read(out, binary).mesh.faces, m.mesh.faces);
  }
}

// A unit square of two triangles, its corners at different heights.
TriangleMesh two_triangle_square() {
  TriangleMesh square;
  square.vertices = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.2}, {1.0, 1.0, 0.6}, {0.0, 1.0, 0.1}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  return square;
}

// `square`'s refinement with its diagonal 0–2 split at the midpoint (vertex 4): four faces, two in each input triangle.
MeshRefinement square_split_on_its_diagonal(const TriangleMesh& square) {
  MeshRefinement refinement;
  refinement.mesh.vertices = square.vertices;
  refinement.mesh.vertices.push_back({0.5, 0.5, 0.3});
  refinement.mesh.faces = {{0, 1, 4}, {0, 4, 3}, {4, 1, 2}, {4, 2, 3}};
  refinement.source_face = {0, 1, 0, 1};
  refinement.new_vertices = {{0, {0.5, 0.0, 0.5}}};  // on face 0, halfway from corner 0 to corner 2
  refinement.split_edges = 1;
  return refinement;
}

// Refinement split the diagonal of a two-triangle square at its midpoint (vertex 4): the refined primitive gets every
// attribute for the new vertex, interpolated on its input triangle; one glTF vertex where the triangles share their
// glTF vertices, two where they are split (a seam), and the indices of the four output faces.
TEST(GltfOutput, RefinedFacesGetNewVerticesWithTheirAttributesInterpolated) {
  const TriangleMesh square = two_triangle_square();
  const MeshRefinement refinement = square_split_on_its_diagonal(square);
  for (const bool split : {false, true}) {
    for (const bool binary : {false, true}) {
      SCOPED_TRACE(std::string(split ? "split" : "shared") + (binary ? " glb" : " gltf"));
      GltfFileOptions options;
      options.split = split;
      const std::string input = binary ? testing::glb_bytes(testing::gltf_parts(square, options))
                                       : testing::gltf_text(testing::gltf_parts(square, options));
      const GltfMesh m = read(input, binary);
      ASSERT_TRUE(m.unrefinable.empty()) << m.unrefinable;
      const MeshRegion region = disk_region(refinement.mesh, {0, 1, 2, 3}, kFile);
      std::vector<std::array<double, 2>> uvs;
      for (const int v : region.vertices) uvs.push_back({0.1 + 0.2 * v, 0.8 - 0.1 * v});
      const std::string out = textured_gltf_bytes(m, region, uvs, std::nullopt, &refinement);

      const tinygltf::Model after = load_model(out, binary);
      const tinygltf::Primitive& p = after.meshes[0].primitives[0];
      const std::size_t input_vertices = split ? 6 : 4;
      const std::size_t added = split ? 2 : 1;  // across the seam, one glTF vertex on each side
      const std::vector<float> position = testing::accessor_floats(after, p.attributes.at("POSITION"));
      ASSERT_EQ(position.size(), 3 * (input_vertices + added));
      for (std::size_t g = input_vertices; g < input_vertices + added; ++g) {
        EXPECT_FLOAT_EQ(position[3 * g], 0.5F);
        EXPECT_FLOAT_EQ(position[3 * g + 1], 0.5F);
        EXPECT_FLOAT_EQ(position[3 * g + 2], 0.3F);  // (0 + 0.6) / 2: corners 0 and 2
      }
      const tinygltf::Accessor& position_accessor = after.accessors.at(p.attributes.at("POSITION"));
      EXPECT_EQ(position_accessor.minValues, (std::vector<double>{0.0, 0.0, 0.0}));
      EXPECT_NEAR(position_accessor.maxValues.at(2), 0.6, 1e-7);
      const std::vector<float> normal = testing::accessor_floats(after, p.attributes.at("NORMAL"));
      const std::vector<float> second = testing::accessor_floats(after, p.attributes.at("TEXCOORD_1"));
      const std::vector<float> uv = testing::accessor_floats(after, p.attributes.at("TEXCOORD_0"));
      ASSERT_EQ(normal.size(), 3 * (input_vertices + added));
      ASSERT_EQ(uv.size(), 2 * (input_vertices + added));
      for (std::size_t g = input_vertices; g < input_vertices + added; ++g) {
        EXPECT_EQ((std::array<float, 3>{normal[3 * g], normal[3 * g + 1], normal[3 * g + 2]}),
                  (std::array<float, 3>{0.0F, 0.0F, 1.0F}));
        EXPECT_FLOAT_EQ(second[2 * g], 0.25F);
        EXPECT_FLOAT_EQ(second[2 * g + 1], 0.75F);
        EXPECT_EQ(uv[2 * g], static_cast<float>(uvs[region.local_vertex[4]][0]));
        EXPECT_EQ(uv[2 * g + 1], static_cast<float>(uvs[region.local_vertex[4]][1]));
      }
      // The indices: every output face, its corners at glTF vertices of its own position.
      const tinygltf::Accessor& indices = after.accessors.at(p.indices);
      ASSERT_EQ(indices.count, 12u);
      EXPECT_EQ(indices.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
      // Read back by texwarp: welded, the refined faces.
      const GltfMesh back = read(out, binary);
      EXPECT_EQ(back.mesh.faces, refinement.mesh.faces);
      ASSERT_EQ(back.mesh.vertex_count(), 5);
      for (int v = 0; v < 5; ++v) {
        EXPECT_NEAR(back.mesh.vertices[v].z, refinement.mesh.vertices[v].z, 1e-7);
      }
      // Faces 0 and 2 lie in input triangle 0, faces 1 and 3 in triangle 1: with split vertices, their new corners
      // are the two different glTF vertices.
      std::set<std::uint32_t> new_corners;
      for (const std::uint32_t corner : back.corners) {
        if (corner >= input_vertices) new_corners.insert(corner);
      }
      EXPECT_EQ(new_corners.size(), added);
      if (split) {
        EXPECT_NE(back.corners[2], back.corners[4]);  // face 0's corner 2 and face 1's corner 1: the new vertex
      } else {
        EXPECT_EQ(back.corners[2], back.corners[4]);
      }
    }
  }
}

// A partial region whose boundary edge was split (the square's diagonal, the region input triangle 0's parts): the
// face outside takes the new vertex too. Across a UV seam (split glTF vertices) the outside's copy of it is used by no
// region face and keeps the outside's own TEXCOORD_0, interpolated on its input triangle, not the region's UV; where
// the sides share glTF vertices, the one copy takes the region's UV as every shared boundary vertex does.
TEST(GltfOutput, TheOutsidesCopyOfASplitBoundaryVertexKeepsTheOutsidesUvs) {
  const TriangleMesh square = two_triangle_square();
  const MeshRefinement refinement = square_split_on_its_diagonal(square);
  const MeshRegion region = disk_region(refinement.mesh, {0, 2}, kFile);
  std::vector<std::array<double, 2>> uvs;
  for (const int v : region.vertices) uvs.push_back({0.1 + 0.2 * v, 0.8 - 0.1 * v});
  for (const bool split : {false, true}) {
    SCOPED_TRACE(split ? "split" : "shared");
    GltfFileOptions options;
    options.split = split;
    const GltfMesh m = read(testing::glb_bytes(testing::gltf_parts(square, options)), true);
    const std::string out = textured_gltf_bytes(m, region, uvs, std::nullopt, &refinement);
    const tinygltf::Model after = load_model(out, true);
    const tinygltf::Primitive& p = after.meshes[0].primitives[0];
    const std::vector<float> uv = testing::accessor_floats(after, p.attributes.at("TEXCOORD_0"));
    const GltfMesh back = read(out, true);
    // The glTF vertex of the new vertex in each output face: face 1 (outside) has it as corner 1, face 0 as corner 2.
    const std::size_t outside = back.corners[3 * 1 + 1];
    const std::size_t inside = back.corners[3 * 0 + 2];
    const std::array<float, 2> region_uv{static_cast<float>(uvs[region.local_vertex[4]][0]),
                                         static_cast<float>(uvs[region.local_vertex[4]][1])};
    EXPECT_EQ((std::array<float, 2>{uv[2 * inside], uv[2 * inside + 1]}), region_uv);
    if (!split) {
      EXPECT_EQ(outside, inside);
      continue;
    }
    ASSERT_NE(outside, inside);
    // Input triangle 1's glTF vertices at mesh vertices 0 and 2 (corners 0 and 1 of face {0, 2, 3}).
    const std::array<double, 2> a = m.texcoord0[m.corners[3 * 1 + 0]];
    const std::array<double, 2> b = m.texcoord0[m.corners[3 * 1 + 1]];
    EXPECT_FLOAT_EQ(uv[2 * outside], static_cast<float>(0.5 * (a[0] + b[0])));
    EXPECT_FLOAT_EQ(uv[2 * outside + 1], static_cast<float>(0.5 * (a[1] + b[1])));
    EXPECT_NE((std::array<float, 2>{uv[2 * outside], uv[2 * outside + 1]}), region_uv);
  }
}

// An attribute added to a test file: `values` (count × components, in glTF vertex order) stored as `component_type`
// in a buffer view of its own at the end of the buffer; the primitive's (or morph target `target`'s) `name`.
template <class T>
void add_attribute(GltfParts& parts, const std::string& name, int component_type, const char* shape,
                   const std::vector<T>& values, int target = -1) {
  while (parts.bin.size() % 4 != 0) parts.bin.push_back('\0');
  const std::size_t offset = parts.bin.size();
  parts.bin.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  nlohmann::json& views = parts.json["bufferViews"];
  views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * sizeof(T)}});
  const std::size_t components = std::string(shape) == "VEC4" ? 4 : std::string(shape) == "VEC2" ? 2 : 3;
  nlohmann::json& accessors = parts.json["accessors"];
  accessors.push_back({{"bufferView", views.size() - 1},
                       {"componentType", component_type},
                       {"count", values.size() / components},
                       {"type", shape}});
  nlohmann::json& primitive = parts.json["meshes"][0]["primitives"][0];
  if (target < 0) {
    primitive["attributes"][name] = accessors.size() - 1;
  } else {
    primitive["targets"][target][name] = accessors.size() - 1;
  }
  parts.json["buffers"][0]["byteLength"] = parts.bin.size();
}

// A new vertex at 0.4·corner 0 + 0.6·corner 2 of a square's triangle 0, with the attributes a DCC writes: a skin's
// JOINTS_0 and WEIGHTS_0 are its nearest corner's together (interpolated weights would no longer belong to their
// joints), a quantized (short) TEXCOORD_2 is interpolated and written as float, NORMAL is interpolated and
// renormalised, POSITION is the refined mesh's. Attributes sharing an accessor (100 morph targets on one) cost one
// decoded copy in the memory model.
TEST(GltfOutput, NewVerticesTakeSkinsFromTheirNearestCornerAndInterpolateTheRest) {
  TriangleMesh square;
  square.vertices = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.2}, {1.0, 1.0, 0.6}, {0.0, 1.0, 0.1}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  GltfParts parts = testing::gltf_parts(square);
  add_attribute<std::uint16_t>(parts, "JOINTS_0", 5123, "VEC4", {1, 2, 0, 0, 5, 5, 5, 5, 3, 0, 0, 0, 4, 0, 0, 0});
  add_attribute<float>(parts, "WEIGHTS_0", 5126, "VEC4",
                       {0.5F, 0.5F, 0, 0, 0.25F, 0.25F, 0.25F, 0.25F, 1, 0, 0, 0, 1, 0, 0, 0});
  add_attribute<std::int16_t>(parts, "TEXCOORD_2", 5122, "VEC2", {0, 0, 7, 7, 100, 100, 9, 9});
  add_attribute<float>(parts, "NORMAL", 5126, "VEC3", {1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1});
  const GltfMesh m = read(testing::gltf_text(parts), false);
  ASSERT_TRUE(m.unrefinable.empty()) << m.unrefinable;
  MeshRefinement refinement;
  refinement.mesh.vertices = square.vertices;
  refinement.mesh.vertices.push_back({0.6, 0.6, 0.36});
  refinement.mesh.faces = {{0, 1, 4}, {0, 4, 3}, {4, 1, 2}, {4, 2, 3}};
  refinement.source_face = {0, 1, 0, 1};
  refinement.new_vertices = {{0, {0.4, 0.0, 0.6}}};
  refinement.split_edges = 1;
  const MeshRegion region = disk_region(refinement.mesh, {0, 1, 2, 3}, kFile);
  const std::vector<std::array<double, 2>> uvs(5, {0.5, 0.5});
  const tinygltf::Model after = load_model(textured_gltf_bytes(m, region, uvs, std::nullopt, &refinement), false);
  const tinygltf::Primitive& p = after.meshes[0].primitives[0];
  const tinygltf::Accessor& joints = after.accessors.at(p.attributes.at("JOINTS_0"));
  EXPECT_EQ(joints.componentType, 5123);  // as read
  const tinygltf::BufferView& jv = after.bufferViews.at(joints.bufferView);
  std::array<std::uint16_t, 4> j{};
  std::memcpy(j.data(), after.buffers.at(jv.buffer).data.data() + jv.byteOffset + joints.byteOffset + std::size_t{32},
              8);
  EXPECT_EQ(j, (std::array<std::uint16_t, 4>{3, 0, 0, 0}));  // corner 2's
  const std::vector<float> weights = testing::accessor_floats(after, p.attributes.at("WEIGHTS_0"));
  EXPECT_EQ(std::vector<float>(weights.begin() + 16, weights.end()), (std::vector<float>{1, 0, 0, 0}));
  const tinygltf::Accessor& quantized = after.accessors.at(p.attributes.at("TEXCOORD_2"));
  EXPECT_EQ(quantized.componentType, 5126);
  const std::vector<float> uv2 = testing::accessor_floats(after, p.attributes.at("TEXCOORD_2"));
  EXPECT_FLOAT_EQ(uv2.at(8), 60.0F);
  EXPECT_FLOAT_EQ(uv2.at(9), 60.0F);
  EXPECT_FLOAT_EQ(uv2.at(0), 0.0F);  // the input's values kept
  EXPECT_FLOAT_EQ(uv2.at(4), 100.0F);
  const std::vector<float> normal = testing::accessor_floats(after, p.attributes.at("NORMAL"));
  const double length = std::hypot(0.4, 0.6);
  EXPECT_NEAR(normal.at(12), 0.4 / length, 1e-6);
  EXPECT_NEAR(normal.at(13), 0.6 / length, 1e-6);
  EXPECT_NEAR(normal.at(14), 0.0, 1e-7);
  const std::vector<float> position = testing::accessor_floats(after, p.attributes.at("POSITION"));
  EXPECT_EQ((std::vector<float>(position.begin() + 12, position.end())), (std::vector<float>{0.6F, 0.6F, 0.36F}));

  // Shared accessors: the memory model counts each once, however many attributes point at it.
  GltfParts morphs = testing::gltf_parts(square);
  const int positions = morphs.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>();
  for (int t = 0; t < 100; ++t) morphs.json["meshes"][0]["primitives"][0]["targets"][t]["POSITION"] = positions;
  const GltfMesh shared = read(testing::gltf_text(morphs), false);
  ASSERT_TRUE(shared.unrefinable.empty()) << shared.unrefinable;
  EXPECT_EQ(shared.attributes.size(), 103u);  // NORMAL, POSITION, TEXCOORD_1 and the 100 targets
  EXPECT_EQ(shared.refinement_bytes, read(testing::gltf_text(testing::gltf_parts(square)), false).refinement_bytes);
}

// A primitive whose vertex data is compressed is read, but cannot take new vertices: said, and refused by the writer.
TEST(GltfInput, CompressedVertexDataIsReadButNotRefinable) {
  GltfParts parts = testing::gltf_parts(testing::flat_grid(3, 3));
  parts.json["extensionsUsed"] = {"EXT_meshopt_compression"};
  // Named by the file but used by none of the primitive's buffer views: refinable.
  EXPECT_TRUE(read(testing::gltf_text(parts), false).unrefinable.empty());
  const int normal = parts.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].get<int>();
  const int view = parts.json["accessors"][normal]["bufferView"].get<int>();
  parts.json["bufferViews"][view]["extensions"]["EXT_meshopt_compression"] = {{"buffer", 0}, {"mode", "ATTRIBUTES"}};
  const GltfMesh m = read(testing::gltf_text(parts), false);
  EXPECT_EQ(m.mesh.face_count(), 18);
  EXPECT_THAT(m.unrefinable, HasSubstr("compressed (EXT_meshopt_compression)"));
  EXPECT_TRUE(m.attributes.empty());
  const GltfMesh plain = read(testing::gltf_text(testing::gltf_parts(testing::flat_grid(3, 3))), false);
  EXPECT_TRUE(plain.unrefinable.empty());
  ASSERT_EQ(plain.attributes.size(), 3u);  // NORMAL, POSITION, TEXCOORD_1 (TEXCOORD_0 apart)
}

}  // namespace
}  // namespace texwarp::mesh
