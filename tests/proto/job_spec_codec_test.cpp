// Tests of the job contract as typed values: enums and devices decoded once from their name tables, the mesh job's
// features, region and inline mesh decoded in proto, and decode → encode → decode giving equal values.
#include <gtest/gtest.h>

#include "texwarp/proto/device_spec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"

namespace texwarp::proto {
namespace {

const std::string kBlob = "sha256:" + std::string(64, 'b');

JobSpec decode(const std::string& text) { return decode_job_spec(parse_json(text, "job.json")); }

// decode(encode(spec)) equals spec, and encoding is a fixed point.
void expect_round_trip(const JobSpec& spec) {
  const nlohmann::json encoded = encode_job_spec(spec);
  const JobSpec again = decode_job_spec(encoded);
  EXPECT_TRUE(again == spec) << encoded.dump();
  EXPECT_EQ(encode_job_spec(again), encoded);
}

// The InputError's message for a job that must be rejected.
std::string rejection(const std::string& text) {
  try {
    decode(text);
  } catch (const InputError& e) {
    return e.message_without_file();
  }
  return "(accepted)";
}

const std::string kMeshJob = R"({"name": "head", "image": {"blob": ")" + kBlob + R"("},
  "mesh": {"source": {"inline": {"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]],
                                 "triangles": [[0, 1, 2], [1, 3, 2]]}},
           "region": {"boundary": [0, 1, 3, 2], "seed_face": 1},
           "features": {"alpha": 2.5, "prealign": "none", "tolerance_px": 0.02, "snap_tolerance": 0.1,
                        "features": [
             {"id": "eye", "source": [10, 20], "target": {"face": 0, "barycentric": [0.2, 0.3, 0.5]}},
             {"source": [40, 50], "target": {"point": [0.5, 0.5, 0.1]},
              "source_frame": {"angle_deg": 15, "scale": 2},
              "target_frame": {"direction": [1, 0, 0], "texels_per_unit": 64}},
             {"id": "v", "source": [70, 5], "target": {"vertex": 3}}]},
           "margin_px": 3, "obj_uv": "warped", "per_triangle": true},
  "output": {"image": false, "uv_origin": "top_left", "file_format": "tiff", "pixel_format": "uint16"},
  "options": {"device": "opencl:gpu", "exact": true}})";

TEST(JobContract, ImageJobRoundTripsAsTypedValues) {
  const JobSpec spec = decode(R"({"image": {"path": "/data/t.png"},
    "warp": {"alpha": 3, "prealign": "none", "tolerance_px": 0.5,
             "features": [{"id": "g", "source": [1, 2], "target": [3, 4],
                           "source_frame": {"angle_deg": 10, "scale": 2}, "target_frame": {"angle_deg": 20}},
                          {"source": [5.25, 6], "target": [7, 8.125]}]},
    "output": {"width": 64, "interpolation": "bicubic", "border": "clamp", "pixel_format": "float",
               "file_format": "exr"},
    "options": {"tolerance_px": 0.25, "device": "cpu", "jacobian_check": true}})");
  EXPECT_EQ(spec.warp->prealign, Prealign::kNone);
  EXPECT_EQ(spec.output.interpolation, Interpolation::kBicubic);
  EXPECT_EQ(spec.output.border, Border::kClamp);
  EXPECT_EQ(spec.output.pixel_format, PixelFormat::kFloat);
  EXPECT_EQ(spec.output.file_format, FileFormat::kExr);
  EXPECT_EQ(spec.output.uv_origin, UvOrigin::kBottomLeft);
  EXPECT_EQ(spec.options.device, DeviceSpec::cpu());
  EXPECT_EQ(spec.warp->features[0].target_frame->scale, 1.0);  // the default, written out by the encoder
  expect_round_trip(spec);
}

TEST(JobContract, MeshJobIsDecodedWholeAndRoundTrips) {
  const JobSpec spec = decode(kMeshJob);
  ASSERT_TRUE(spec.mesh);
  const MeshJobSpec& m = *spec.mesh;
  EXPECT_EQ(m.source.mesh.vertices[3][2], 0.5);
  EXPECT_EQ(m.source.mesh.triangles[1], (std::array<int, 3>{1, 3, 2}));
  ASSERT_TRUE(m.region);
  EXPECT_EQ(m.region->boundary, (std::vector<int>{0, 1, 3, 2}));
  EXPECT_EQ(m.region->seed_face, 1);
  EXPECT_EQ(m.features.alpha, 2.5);
  EXPECT_EQ(m.features.prealign, Prealign::kNone);
  EXPECT_EQ(m.features.snap_tolerance, 0.1);
  ASSERT_EQ(m.features.features.size(), 3u);
  const auto& face = std::get<FaceTargetSpec>(m.features.features[0].target);
  EXPECT_EQ(face.face, 0);
  EXPECT_EQ(face.barycentric[2], 0.5);
  EXPECT_EQ(std::get<PointTargetSpec>(m.features.features[1].target).point[2], 0.1);
  EXPECT_EQ(m.features.features[1].source_frame->angle_deg, 15.0);
  EXPECT_EQ(m.features.features[1].target_frame->texels_per_unit, 64.0);
  EXPECT_EQ(std::get<VertexTargetSpec>(m.features.features[2].target).vertex, 3);
  EXPECT_EQ(m.obj_uv, ObjUv::kWarped);
  EXPECT_EQ(spec.output.uv_origin, UvOrigin::kTopLeft);
  EXPECT_EQ(spec.output.pixel_format, PixelFormat::kUint16);
  EXPECT_EQ(spec.options.device, DeviceSpec::opencl("gpu"));
  expect_round_trip(spec);
}

TEST(JobContract, MeshSourcesAndFaceRegionsRoundTrip) {
  for (const std::string& source :
       {R"({"blob": ")" + kBlob + R"(", "format": "json"})", std::string(R"({"path": "/m/spot.OBJ"})"),
        std::string(R"({"obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"})")}) {
    std::string job = R"({"image": {"blob": ")" + kBlob + R"("}, "mesh": {"source": )";
    job.append(source).append(R"(, "region": {"faces": [4, 0, 7]}, "features": {"features": []}}})");
    const JobSpec spec = decode(job);
    EXPECT_EQ(spec.mesh->region->faces, (std::vector<int>{4, 0, 7})) << source;
    expect_round_trip(spec);
  }
  EXPECT_EQ(decode(R"({"image": {"blob": ")" + kBlob + R"("}, "mesh": {"source": {"path": "/m/spot.OBJ"},
                     "features": {"features": []}}})")
                .mesh->source.format,
            MeshFormat::kObj);
}

TEST(JobContract, GltfSourcesNameTheirPrimitive) {
  const auto job = [](const std::string& source) {
    return R"({"image": {"blob": ")" + kBlob + R"("}, "mesh": {"source": )" + source +
           R"(, "features": {"features": []}}})";
  };
  const JobSpec named = decode(job(R"({"path": "/m/head.GLB", "gltf": {"mesh": "Head", "primitive": 2}})"));
  EXPECT_EQ(named.mesh->source.format, MeshFormat::kGlb);
  EXPECT_EQ(named.mesh->source.gltf->mesh_name, "Head");
  EXPECT_EQ(named.mesh->source.gltf->primitive, 2);
  expect_round_trip(named);
  const JobSpec indexed = decode(job(R"({"blob": ")" + kBlob + R"(", "format": "gltf", "gltf": {"mesh": 3}})"));
  EXPECT_EQ(indexed.mesh->source.gltf->mesh_index, 3);
  EXPECT_EQ(indexed.mesh->source.gltf->primitive, 0);
  expect_round_trip(indexed);
  EXPECT_EQ(rejection(job(R"({"path": "/m/a.obj", "gltf": {"mesh": 0}})")),
            "$.mesh.source.gltf: \"gltf\" only applies to a glTF mesh (\"format\": \"gltf\" or \"glb\")");
  EXPECT_EQ(rejection(job(R"({"path": "/m/a.gltf", "gltf": {"mesh": -1}})")),
            "$.mesh.source.gltf.mesh: expected a mesh name (string) or a 0-based mesh index, got -1");
  EXPECT_EQ(rejection(job(R"({"path": "/m/a.gltf", "gltf": {"primitiv": 1}})")).rfind("$.mesh.source.gltf", 0), 0u);
}

TEST(JobContract, MeshPartsAreValidatedOfflineWithTheirJobPath) {
  const auto with_mesh = [](const std::string& mesh) {
    return R"({"image": {"blob": ")" + kBlob + R"("}, "mesh": )" + mesh + "}";
  };
  const std::string source = R"("source": {"inline": {"vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,2]]}})";
  EXPECT_EQ(rejection(with_mesh("{" + source + R"(, "features": {"features": [{"source": [1, 2],
              "target": {"face": 0, "barycentric": [0.5, 0.5, 0.5]}}]}})")),
            "$.mesh.features.features[0].target.barycentric: barycentric weights must be ≥ 0 and sum to 1 (got sum "
            "1.500000)");
  EXPECT_EQ(rejection(with_mesh("{" + source + R"(, "features": {"features": [{"source": [1, 2],
              "target": {"vertex": 0}, "target_frame": {"direction": [1, 0, 0], "texels_per_unit": 1}}]}})")),
            "$.mesh.features.features[0]: a gradient feature needs both source_frame and target_frame (only "
            "target_frame given)");
  EXPECT_EQ(rejection(with_mesh("{" + source + R"(, "region": {"faces": [0, 0]}, "features": {"features": []}})")),
            "$.mesh.region.faces[1]: face 0 is listed twice (also at [0])");
  EXPECT_EQ(rejection(with_mesh(R"({"source": {"inline": {"vertices": [[0, 0]], "triangles": []}},
              "features": {"features": []}})")),
            "$.mesh.source.inline.vertices[0]: expected a point [x, y, z] (an array of 3 numbers)");
  EXPECT_EQ(rejection(with_mesh("{" + source + R"(, "features": {"prealign": "affine", "features": []}})")),
            "$.mesh.features.prealign: expected \"similarity\" or \"none\", got \"affine\"");
  EXPECT_EQ(rejection(with_mesh("{" + source + R"(, "features": {"features": []}, "obj_uv": "both"})")),
            "$.mesh.obj_uv: expected \"original\" or \"warped\", got \"both\"");
}

TEST(JobContract, EnumsAreDecodedFromTheirOneTable) {
  EXPECT_EQ(enum_from_name<Border>("repeat"), Border::kRepeat);
  EXPECT_EQ(enum_from_name<Border>("Repeat"), std::nullopt);
  EXPECT_STREQ(to_string(PixelFormat::kHalf), "half");
  EXPECT_EQ(quoted_enum_names<PixelFormat>(), R"("uint8", "uint16", "half" or "float")");
  EXPECT_EQ(enum_names<UvOrigin>(), (std::vector<std::string>{"bottom_left", "top_left"}));
  EXPECT_EQ(parse_enum<JobKind>("mesh", {}), JobKind::kMesh);
  try {
    parse_enum<Interpolation>("nearest", InputLocation::flag("--interp"));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), R"(--interp: expected "bilinear" or "bicubic", got "nearest")");
  }
  EXPECT_EQ(rejection(R"({"image": {"blob": ")" + kBlob + R"("}, "warp": {"features": []},
                          "output": {"interpolation": "nearest"}})"),
            R"($.output.interpolation: expected "bilinear" or "bicubic", got "nearest")");
}

TEST(JobContract, ImageRolesAndTheFilterRoundTripAndRefusalsNameTheirPath) {
  const JobSpec spec = decode_job_spec(nlohmann::json::parse(R"({"image": {"path": "/n.png", "role": "normal",
      "normal_convention": "directx"}, "warp": {"features": []}, "output": {"filter": "point"}})"));
  EXPECT_EQ(spec.image.role, ImageRole::kNormal);
  EXPECT_EQ(spec.image.normal_convention, NormalConvention::kDirectX);
  EXPECT_EQ(spec.output.filter, SamplingFilter::kPoint);
  EXPECT_EQ(decode_job_spec(encode_job_spec(spec)), spec);
  // Defaults: the file's role, the footprint filter; a colour space by any of its names, kept canonical.
  const JobSpec plain = decode_job_spec(nlohmann::json::parse(
      R"({"image": {"blob": ")" + kBlob + R"(", "color_space": "Linear"}, "warp": {"features": []}})"));
  EXPECT_EQ(plain.image.role, std::nullopt);
  EXPECT_EQ(plain.image.color_space, "linear");
  EXPECT_EQ(plain.output.filter, SamplingFilter::kFootprint);
  EXPECT_EQ(decode_job_spec(encode_job_spec(plain)), plain);
  EXPECT_EQ(rejection(R"({"image": {"blob": ")" + kBlob + R"(", "role": "albedo"}, "warp": {"features": []}})"),
            R"($.image.role: expected "color", "data" or "normal", got "albedo")");
  // Another name is an OpenColorIO config's, kept as given (the plan looks it up); an empty one is refused here.
  EXPECT_EQ(decode_job_spec(nlohmann::json::parse(R"({"image": {"blob": ")" + kBlob +
                                                  R"(", "color_space": "ACEScg"}, "warp": {"features": []}})"))
                .image.color_space,
            "ACEScg");
  EXPECT_EQ(rejection(R"({"image": {"blob": ")" + kBlob + R"(", "color_space": ""}, "warp": {"features": []}})"),
            R"($.image.color_space: expected a colour space's name of 1 to 200 bytes without control characters)");
  EXPECT_EQ(rejection(R"({"image": {"blob": ")" + kBlob + R"("}, "warp": {"features": []},
                          "output": {"filter": "ewa"}})"),
            R"($.output.filter: expected "footprint" or "point", got "ewa")");
}

TEST(DeviceSpec, TheGrammarIsParsedHere) {
  EXPECT_EQ(device_from_string("cpu"), DeviceSpec::cpu());
  EXPECT_EQ(device_from_string("opencl"), DeviceSpec::opencl());
  EXPECT_EQ(device_from_string("opencl:NVIDIA H200"), DeviceSpec::opencl("NVIDIA H200"));
  EXPECT_EQ(device_from_string("opencl:a:b")->name, "a:b");
  for (const char* bad : {"", "gpu", "opencl:", "OpenCL", "cpu:0", "opencl "}) {
    EXPECT_EQ(device_from_string(bad), std::nullopt) << bad;
  }
  for (const char* text : {"cpu", "opencl", "opencl:pocl"}) EXPECT_EQ(device_from_string(text)->str(), text);
  try {
    parse_device("gpu", JsonPath{"options", "device"});
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), R"($.options.device: expected "cpu", "opencl" or "opencl:<device name>", got "gpu")");
  }
}

}  // namespace
}  // namespace texwarp::proto
