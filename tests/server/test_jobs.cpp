// Jobs for the service tests: see test_jobs.hpp.
#include "test_jobs.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/base64.hpp"

namespace texwarp::testing {

std::string test_png(int size) {
  static std::map<int, std::string> cache;
  if (auto it = cache.find(size); it != cache.end()) return it->second;
  Image image(size, size, 3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      float* p = image.pixel(x, y);
      const bool check = ((x / 8) + (y / 8)) % 2 == 0;
      p[0] = static_cast<float>(x) / static_cast<float>(size);
      p[1] = static_cast<float>(y) / static_cast<float>(size);
      p[2] = check ? 0.9f : 0.1f;
    }
  }
  const auto path = std::filesystem::temp_directory_path() /
                    ("texwarp-test-pattern-" + std::to_string(::getpid()) + "-" + std::to_string(size) + ".png");
  write_image(path.string(), image, PixelFormat::kUint8);
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  std::filesystem::remove(path);
  return cache[size] = ss.str();
}

nlohmann::json image_job_features() {
  return nlohmann::json::parse(R"([
    {"id": "a", "source": [16, 16], "target": [18, 15]},
    {"id": "b", "source": [48, 16], "target": [47, 18]},
    {"id": "c", "source": [32, 48], "target": [33, 46]},
    {"id": "g", "source": [32, 30], "target": [31, 31],
     "source_frame": {"angle_deg": 0, "scale": 1}, "target_frame": {"angle_deg": 15, "scale": 1.1}}])");
}

nlohmann::json image_job(int output_side) {
  nlohmann::json job = {{"name", "test image job"},
                        {"image", {{"base64", proto::base64_encode(test_png(64))}}},
                        {"warp", {{"alpha", 2.0}, {"tolerance_px", 0.01}, {"features", image_job_features()}}}};
  if (output_side > 0) job["output"] = {{"width", output_side}, {"height", output_side}};
  return job;
}

nlohmann::json slow_image_job(int output_side) {
  nlohmann::json features = nlohmann::json::array();
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      const double sx = 6 + i * 10.4;
      const double sy = 6 + j * 10.4;
      // Deterministic small displacements (no collisions: spacing 10.4 px, moves ≤ 2 px).
      const double dx = 2.0 * std::sin(1.7 * i + 0.3 * j);
      const double dy = 2.0 * std::cos(0.9 * i + 1.3 * j);
      features.push_back({{"source", {sx, sy}}, {"target", {sx + dx, sy + dy}}});
    }
  }
  return {{"name", "slow test job"},
          {"image", {{"base64", proto::base64_encode(test_png(64))}}},
          {"warp", {{"alpha", 2.0}, {"tolerance_px", 0.001}, {"features", features}}},
          {"output", {{"width", output_side}, {"height", output_side}}},
          {"options", {{"exact", true}}}};  // a pathline per pixel: slow, with progress after every tile
}

nlohmann::json mesh_job() {
  constexpr int kQuads = 6;
  nlohmann::json vertices = nlohmann::json::array();
  nlohmann::json triangles = nlohmann::json::array();
  for (int j = 0; j <= kQuads; ++j) {
    for (int i = 0; i <= kQuads; ++i) vertices.push_back({i, j, 0.0});
  }
  for (int j = 0; j < kQuads; ++j) {
    for (int i = 0; i < kQuads; ++i) {
      const int a = j * (kQuads + 1) + i;
      const int b = a + 1;
      const int c = a + kQuads + 1;
      const int d = c + 1;
      triangles.push_back({a, b, d});
      triangles.push_back({a, d, c});
    }
  }
  const auto vertex = [](int i, int j) { return j * (kQuads + 1) + i; };
  nlohmann::json features = nlohmann::json::array({
      {{"id", "p11"}, {"source", {12, 50}}, {"target", {{"vertex", vertex(1, 1)}}}},
      {{"id", "p51"}, {"source", {52, 52}}, {"target", {{"vertex", vertex(5, 1)}}}},
      {{"id", "p55"}, {"source", {51, 12}}, {"target", {{"vertex", vertex(5, 5)}}}},
      {{"id", "p15"}, {"source", {12, 13}}, {"target", {{"vertex", vertex(1, 5)}}}},
      {{"id", "p33"}, {"source", {33, 31}}, {"target", {{"vertex", vertex(3, 3)}}}},
  });
  return {{"name", "test mesh job"},
          {"image", {{"base64", proto::base64_encode(test_png(64))}}},
          {"mesh",
           {{"source", {{"inline", {{"vertices", vertices}, {"triangles", triangles}}}}},
            {"features", {{"alpha", 2.0}, {"tolerance_px", 0.01}, {"features", features}}}}}};
}

}  // namespace texwarp::testing
