// Input faces ↔ triangles: see input_faces.hpp.
#include "texwarp/mesh/input_faces.hpp"

#include <algorithm>
#include <string>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {
namespace {

std::string no_such_face(int face, const InputFaces& faces) {
  return "face " + std::to_string(face) + " does not exist (the mesh has " + std::to_string(faces.count()) + " faces)";
}

}  // namespace

InputFaces InputFaces::identity(int triangles) {
  InputFaces faces;
  faces.of_triangle.resize(static_cast<std::size_t>(triangles));
  faces.first_triangle.resize(static_cast<std::size_t>(triangles) + 1);
  for (int i = 0; i < triangles; ++i) faces.of_triangle[i] = faces.first_triangle[i] = i;
  faces.first_triangle[triangles] = triangles;
  return faces;
}

void InputFaces::add_face(int triangles) {
  if (first_triangle.empty()) first_triangle.push_back(0);
  const int face = count();
  for (int k = 0; k < triangles; ++k) of_triangle.push_back(face);
  first_triangle.push_back(first_triangle.back() + triangles);
}

proto::RegionSpec region_on_triangles(const proto::RegionSpec& spec, const InputFaces& faces,
                                      const proto::InputLocation& where) {
  if (faces.all_triangles()) return spec;
  const auto at = [&](JsonPath path) { return proto::InputLocation(std::move(path)).in_file(where.file_name()); };
  proto::RegionSpec out = spec;
  if (spec.is_curve()) {
    if (spec.seed_face >= faces.count())
      throw InputError(at(JsonPath{"seed_face"}), no_such_face(spec.seed_face, faces));
    out.seed_face = faces.first_triangle[spec.seed_face];
    return out;
  }
  out.faces.clear();
  for (std::size_t i = 0; i < spec.faces.size(); ++i) {
    const int f = spec.faces[i];
    if (f >= faces.count()) throw InputError(at(JsonPath{"faces"}.index(i)), no_such_face(f, faces));
    for (int t = faces.first_triangle[f]; t < faces.first_triangle[f + 1]; ++t) out.faces.push_back(t);
  }
  return out;
}

SurfaceFeatureSet features_on_triangles(SurfaceFeatureSet set, const InputFaces& faces) {
  if (faces.all_triangles()) return set;
  for (std::size_t i = 0; i < set.features.size(); ++i) {
    auto* target = std::get_if<FaceTarget>(&set.features[i].target);
    if (target == nullptr) continue;
    const JsonPath where = JsonPath{"features"}.index(i).key("target").key("face");
    if (target->face >= faces.count()) throw InputError(where, no_such_face(target->face, faces));
    if (faces.triangles_of(target->face) != 1) {
      throw InputError(where, "face " + std::to_string(target->face) +
                                  " is a polygon: barycentric weights need a triangle (give a \"point\" or "
                                  "\"vertex\" target on it instead)");
    }
    target->face = faces.first_triangle[target->face];
  }
  return set;
}

int region_face_count(std::span<const int> triangles, const InputFaces& faces, bool refined) {
  if (refined || faces.all_triangles()) return static_cast<int>(triangles.size());
  std::vector<bool> seen(static_cast<std::size_t>(faces.count()), false);
  int count = 0;
  for (const int t : triangles) {
    if (!seen[faces.of_triangle[t]]) ++count;
    seen[faces.of_triangle[t]] = true;
  }
  return count;
}

void name_input_faces(proto::MeshMappingReport& report, const InputFaces& faces,
                      std::span<const int> region_triangles) {
  report.mesh.faces = faces.count();
  if (faces.all_triangles()) return;
  const auto input_face = [&](int triangle) { return faces.of_triangle[triangle]; };
  // Ids on the input mesh, with or without `refine`: where features lie, the faces LSCM flipped (before any
  // split), where added vertices lie, and every source_face.
  for (auto& f : report.features) f.face = input_face(f.face);
  if (report.embedding) {
    std::vector<int>& lscm_flipped = report.embedding->lscm_flipped_faces;
    for (int& f : lscm_flipped) f = input_face(f);
    std::sort(lscm_flipped.begin(), lscm_flipped.end());
    lscm_flipped.erase(std::unique(lscm_flipped.begin(), lscm_flipped.end()), lscm_flipped.end());
  }
  std::vector<proto::FlippedFaceReport> no_flips;
  std::vector<proto::FlippedFaceReport>& flips = report.flips ? *report.flips : no_flips;
  if (report.vertices) {
    for (auto& v : *report.vertices) {
      if (v.source) v.source->face = input_face(v.source->face);
    }
  }
  if (report.refinement && report.refinement->added_faces > 0) {
    // The output's faces are triangles (the OBJ written anew); where they came from is said in input faces.
    if (report.triangles) {
      for (auto& t : *report.triangles) {
        if (t.source_face) t.source_face = input_face(*t.source_face);
      }
    }
    for (auto& f : flips) {
      if (f.source_face) f.source_face = input_face(*f.source_face);
    }
    return;
  }
  report.region.faces = region_face_count(region_triangles, faces, false);
  if (report.triangles) {
    for (auto& t : *report.triangles) t.face = input_face(t.face);
  }
  for (auto& f : flips) f.face = input_face(f.face);
}

}  // namespace texwarp::mesh
