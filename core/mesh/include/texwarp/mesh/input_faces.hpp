// InputFaces: which face of the input file (an OBJ f line, quads and n-gons included; a glTF triangle) each triangle
// of the TriangleMesh came from. Region face ids and face targets speak of input faces; reports name them.
#pragma once

#include <span>
#include <vector>

#include "texwarp/mesh/surface_feature.hpp"
#include "texwarp/proto/input_location.hpp"
#include "texwarp/proto/job_report.hpp"
#include "texwarp/proto/region_spec.hpp"

namespace texwarp::mesh {

struct InputFaces {
  std::vector<int> of_triangle;     // per triangle: its input face
  std::vector<int> first_triangle;  // per input face: its first triangle (a face's triangles are consecutive); + end

  int count() const { return static_cast<int>(first_triangle.size()) - 1; }
  int triangles_of(int face) const { return first_triangle[face + 1] - first_triangle[face]; }
  bool all_triangles() const { return static_cast<int>(of_triangle.size()) == count(); }

  static InputFaces identity(int triangles);  // every input face a triangle
  void add_face(int triangles);               // the next input face, made of the next `triangles` triangles
};

// The region over triangles: a face set's faces become all their triangles, a seed face its first triangle. An
// input face id out of range is an InputError at `where` (a file or none) under "$.faces[i]" / "$.seed_face".
proto::RegionSpec region_on_triangles(const proto::RegionSpec& spec, const InputFaces& faces,
                                      const proto::InputLocation& where);

// Face targets moved from input faces onto triangles; InputError at "$.features[i].target.face" for a face out of
// range or a face that is a polygon (barycentric weights need a triangle: a point or vertex target works there).
SurfaceFeatureSet features_on_triangles(SurfaceFeatureSet set, const InputFaces& faces);

// The faces of a region as the outputs name them: the input faces with a triangle among `triangles`, or with
// `refined` (the OBJ written anew holds triangles) the triangles themselves.
int region_face_count(std::span<const int> triangles, const InputFaces& faces, bool refined);

// The report in the input's faces: mesh.faces and region.faces count input faces (`region_triangles`: the region's
// triangles); ids on the input mesh (placed features, lscm_flipped_faces, added vertices' source, source_face) name
// input faces with or without `refine`; per-triangle entries and flips name input faces, or with `refine` (the
// report's refinement) the output's faces (the OBJ written anew holds triangles).
void name_input_faces(proto::MeshMappingReport& report, const InputFaces& faces, std::span<const int> region_triangles);

}  // namespace texwarp::mesh
