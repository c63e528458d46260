// The shipped JSON Schemas and OpenAPI document (proto/schema/) against the C++ codec: every document parses and
// declares its dialect; each object of the job schema lists exactly the keys the canonical encoder writes; every
// object rejects an unknown key and every required key is required by the codec too, at the same JSON path; and
// the shipped example jobs decode. (tests/server/validate_against_schemas.py runs a real 2020-12 validator.)
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {
namespace {

namespace fs = std::filesystem;
const fs::path kSchemas = fs::path(TEXWARP_SOURCE_DIR) / "proto" / "schema";

nlohmann::json load(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::set<std::string> keys(const nlohmann::json& object) {
  std::set<std::string> out;
  for (const auto& [k, v] : object.items()) out.insert(k);
  return out;
}

const std::string kBlob = "sha256:" + std::string(64, '0');

nlohmann::json full_image_job() {
  return nlohmann::json::parse(R"({"name": "n", "image": {"blob": ")" + kBlob + R"(", "role": "normal",
    "color_space": "linear", "normal_convention": "directx"},
    "warp": {"alpha": 2, "prealign": "similarity", "tolerance_px": 0.01, "mirror": true,
      "features": [{"id": "g", "source": [1, 2], "target": [3, 4],
                    "source_frame": {"angle_deg": 0, "scale": 1}, "target_frame": {"angle_deg": 10, "scale": 2}}]},
    "output": {"width": 10, "height": 10, "interpolation": "bilinear", "border": "clamp", "filter": "point",
               "pixel_format": "uint8",
               "file_format": "png", "image": true, "uv_origin": "top_left"},
    "options": {"exact": true, "tolerance_px": 0.1, "device": "cpu", "jacobian_check": true,
                "refine": true}})");
}

nlohmann::json full_mesh_job() {
  return nlohmann::json::parse(R"({"image": {"path": "/t.png"},
    "mesh": {"source": {"inline": {"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]}},
             "region": {"faces": [0]}, "features": {"features": []}, "margin_px": 2, "obj_uv": "warped",
             "per_triangle": true, "per_vertex": true}})");
}

// Where the codec refuses `doc`, or "(accepted)".
std::string refusal(const nlohmann::json& doc) {
  try {
    decode_job_spec(doc);
  } catch (const InputError& e) {
    return e.where().str();
  }
  return "(accepted)";
}

// "$.warp.features[0]" → JSON pointer "/warp/features/0".
nlohmann::json::json_pointer pointer(const std::string& path) {
  std::string p;
  for (std::size_t i = 1; i < path.size(); ++i) {
    if (path[i] == '.' || path[i] == '[') {
      p += '/';
    } else if (path[i] != ']') {
      p += path[i];
    }
  }
  return nlohmann::json::json_pointer(p);
}

TEST(Schemas, EveryDocumentParsesAndDeclaresItsDialect) {
  int schemas = 0;
  for (const auto& entry : fs::directory_iterator(kSchemas)) {
    const nlohmann::json doc = load(entry.path());
    if (entry.path().filename() == "openapi.json") {
      EXPECT_EQ(doc["openapi"], "3.1.0");
      EXPECT_TRUE(doc["paths"].contains("/v1/jobs"));
      continue;
    }
    ++schemas;
    EXPECT_EQ(doc["$schema"], "https://json-schema.org/draft/2020-12/schema") << entry.path();
    // Its file name: relative, so that the file names in $refs resolve against where the schema was read from
    // (this folder, or /v1/schemas/ on a server), by Redocly and JSON Schema validators alike.
    EXPECT_EQ(doc["$id"], entry.path().filename().string());
  }
  EXPECT_GE(schemas, 6);
}

// Every $ref of every document resolves from the files of proto/schema/ alone: "#/<pointer>" within the document,
// "<file>" or "<file>#/<pointer>" in a file beside it (what Redocly and client generators resolve; no urn: or
// other scheme, no folder). texwarpd serves openapi.json bundled (tests/server/generate_client.sh lints both).
TEST(Schemas, EveryRefResolvesBesideTheDocument) {
  int external = 0;
  for (const auto& entry : fs::directory_iterator(kSchemas)) {
    const std::string name = entry.path().filename().string();
    const nlohmann::json doc = load(entry.path());
    const std::function<void(const nlohmann::json&)> visit = [&](const nlohmann::json& j) {
      if (j.is_object()) {
        if (auto it = j.find("$ref"); it != j.end() && it->is_string()) {
          const std::string ref = it->get<std::string>();
          const std::size_t hash = ref.find('#');
          const std::string file = ref.substr(0, hash);
          const std::string fragment = hash == std::string::npos ? "" : ref.substr(hash + 1);
          nlohmann::json target = doc;
          if (!file.empty()) {
            ++external;
            ASSERT_EQ(file.find_first_of("/:"), std::string::npos) << name << ": " << ref;
            ASSERT_TRUE(fs::exists(kSchemas / file)) << name << ": " << ref;
            target = load(kSchemas / file);
          }
          EXPECT_TRUE(fragment.empty() || target.contains(nlohmann::json::json_pointer(fragment)))
              << name << ": " << ref;
        }
      }
      if (j.is_structured()) {
        for (const auto& child : j) visit(child);
      }
    };
    visit(doc);
  }
  EXPECT_GE(external, 15);
}

TEST(Schemas, JobObjectsListExactlyTheKeysTheEncoderWrites) {
  const nlohmann::json schema = load(kSchemas / "job.schema.json");
  const auto& defs = schema["$defs"];
  const nlohmann::json image = encode_job_spec(decode_job_spec(full_image_job()));
  const nlohmann::json mesh = encode_job_spec(decode_job_spec(full_mesh_job()));
  auto top = keys(image);
  top.insert({"mesh", "images"});  // the other kind of job, and a texture set instead of one image
  EXPECT_EQ(keys(schema["properties"]), top);
  EXPECT_EQ(keys(defs["warp"]["properties"]), keys(image["warp"]));
  EXPECT_EQ(keys(defs["feature"]["properties"]), keys(image["warp"]["features"][0]));
  EXPECT_EQ(keys(defs["frame"]["properties"]), keys(image["warp"]["features"][0]["source_frame"]));
  EXPECT_EQ(keys(defs["output"]["properties"]), keys(image["output"]));
  EXPECT_EQ(keys(defs["options"]["properties"]), keys(image["options"]));
  EXPECT_EQ(keys(defs["meshJob"]["properties"]), keys(mesh["mesh"]));
  auto image_keys = keys(image["image"]);  // one of the sources, and what the image holds
  image_keys.insert({"base64", "path", "tiles"});
  EXPECT_EQ(keys(defs["imageSource"]["properties"]), image_keys);
  // A UDIM tile: its number and one of its two sources.
  nlohmann::json tiled = full_image_job();
  tiled["image"] = {
      {"tiles", {{{"tile", 1001}, {"blob", "sha256:" + std::string(64, 'a')}}, {{"tile", 1002}, {"base64", "aGk="}}}}};
  const nlohmann::json tiles = encode_job_spec(decode_job_spec(tiled))["image"]["tiles"];
  auto tile_keys = keys(tiles[0]);
  tile_keys.merge(keys(tiles[1]));
  EXPECT_EQ(keys(defs["udimTile"]["properties"]), tile_keys);
  EXPECT_EQ(keys(defs["meshSource"]["properties"]),
            (std::set<std::string>{"blob", "path", "inline", "obj", "format", "gltf"}));
}

TEST(Schemas, UnknownKeysAreRejectedWhereTheSchemaForbidsThem) {
  const nlohmann::json schema = load(kSchemas / "job.schema.json");
  EXPECT_EQ(schema["additionalProperties"], false);
  // Each object the codec reads strictly, in both example documents.
  const std::vector<std::pair<nlohmann::json, std::string>> objects = {
      {full_image_job(), "$"},
      {full_image_job(), "$.image"},
      {full_image_job(), "$.warp"},
      {full_image_job(), "$.warp.features[0]"},
      {full_image_job(), "$.warp.features[0].source_frame"},
      {full_image_job(), "$.output"},
      {full_image_job(), "$.options"},
      {full_mesh_job(), "$.mesh"},
      {full_mesh_job(), "$.mesh.source"}};
  for (const auto& [doc, path] : objects) {
    nlohmann::json bad = doc;
    bad[pointer(path)]["zzz_unknown"] = 1;
    EXPECT_EQ(refusal(bad), (path == "$" ? std::string("$") : path) + ".zzz_unknown") << path;
  }
  for (const char* def : {"imageSource", "feature", "frame", "warp", "meshJob", "meshSource", "output", "options"}) {
    EXPECT_EQ(schema["$defs"][def]["additionalProperties"], false) << def;
  }
}

TEST(Schemas, RequiredKeysAgreeWithTheCodec) {
  const nlohmann::json schema = load(kSchemas / "job.schema.json");
  const auto& defs = schema["$defs"];
  struct Case {
    nlohmann::json doc;
    std::string object;
    nlohmann::json required;
  };
  // At the top level only alternatives are required (image or images, warp or mesh: the schema's allOf/oneOf).
  const std::vector<Case> cases = {{full_image_job(), "$", nlohmann::json::array()},
                                   {full_image_job(), "$.warp", defs["warp"]["required"]},
                                   {full_image_job(), "$.warp.features[0]", defs["feature"]["required"]},
                                   {full_mesh_job(), "$.mesh", defs["meshJob"]["required"]}};
  for (const auto& c : cases) {
    ASSERT_TRUE(c.required.is_array()) << c.object;
    for (const auto& key : c.required) {
      nlohmann::json bad = c.doc;
      bad[pointer(c.object)].erase(key.get<std::string>());
      const std::string where = refusal(bad);
      EXPECT_EQ(where, (c.object == "$" ? std::string("$") : c.object) + "." + key.get<std::string>()) << key;
    }
    // And nothing else is required: the codec accepts the document with every optional key removed.
    nlohmann::json minimal = c.doc;
    auto& object = minimal[pointer(c.object)];
    for (const auto& k : keys(object)) {
      const bool required = std::any_of(c.required.begin(), c.required.end(), [&](const auto& r) { return r == k; });
      const bool alternative = c.object == "$" && (k == "warp" || k == "mesh" || k == "image" || k == "images");
      if (!required && !alternative) object.erase(k);
    }
    EXPECT_EQ(refusal(minimal), "(accepted)") << c.object;
  }
  // The two exclusive alternatives at the top: neither or both refused at "$" / at the second one.
  nlohmann::json neither = full_image_job();
  neither.erase("warp");
  EXPECT_EQ(refusal(neither), "$");
  nlohmann::json both = full_image_job();
  both["mesh"] = full_mesh_job()["mesh"];
  EXPECT_EQ(refusal(both), "$.mesh");
}

TEST(Schemas, ShippedExampleJobsDecode) {
  int jobs = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(TEXWARP_SOURCE_DIR) / "examples")) {
    const std::string name = entry.path().filename().string();
    if (name.find("job") == std::string::npos || entry.path().extension() != ".json") continue;
    ++jobs;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    EXPECT_NO_THROW(decode_job_spec(parse_json(text.str(), name))) << name;
  }
  EXPECT_GE(jobs, 1);
}

}  // namespace
}  // namespace texwarp::proto
