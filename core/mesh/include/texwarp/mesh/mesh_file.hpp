// MeshFile: a mesh as read from its file or job source: the triangles the pipeline works on, the input face of each
// triangle, and what writing the mesh back needs (the OBJ's text, whose lines obj_output keeps; the glTF document).
#pragma once

#include <memory>
#include <string>

#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/input_faces.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/job_spec.hpp"

namespace texwarp::mesh {

struct MeshFile {
  proto::MeshFormat format = proto::MeshFormat::kObj;
  TriangleMesh mesh;                     // quads and n-gons triangulated
  InputFaces faces;                      // per triangle: its face in the input
  std::string obj_text;                  // kObj: the input text
  std::shared_ptr<const GltfMesh> gltf;  // kGltf, kGlb: the document and the primitive read
};

}  // namespace texwarp::mesh
