// CLI input files: see feature_file.hpp.
#include "feature_file.hpp"

#include <fstream>
#include <sstream>

#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::cli {

nlohmann::json read_json_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(InputLocation::file(path), "cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  return in_file(path, [&] { return proto::parse_json(text.str(), path); });
}

proto::WarpSpec read_feature_file(const std::string& path) {
  const nlohmann::json j = read_json_file(path);
  return in_file(path, [&] { return proto::decode_warp_spec(j); });
}

std::vector<std::array<double, 2>> read_points_file(const std::string& path) {
  const nlohmann::json j = read_json_file(path);
  return in_file(path, [&] { return proto::decode_points(j); });
}

WarpProblem problem_from_spec(const proto::WarpSpec& spec, const std::string& path, int mirror_width) {
  return in_file(path, [&] {
    std::vector<Feature> features = features_from_spec(spec);
    if (mirror_width > 0) features = mirror_features(std::move(features), mirror_width);
    return WarpProblem(std::move(features), options_from_spec(spec));
  });
}

WarpProblem load_problem(const std::string& feature_path) {
  const proto::WarpSpec spec = read_feature_file(feature_path);
  return in_file(feature_path, [&] { return WarpProblem(features_from_spec(spec), options_from_spec(spec)); });
}

}  // namespace texwarp::cli
