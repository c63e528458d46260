// Reading the CLI's JSON input files: feature files (WarpSpec) and point lists; errors name the file and
// the JSON path (in_file places any input's errors in the file it came from).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/core/warp_problem.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/warp_spec.hpp"

namespace texwarp::cli {

// Runs f, which reads the content of file `path`; an InputError from it is placed in that file (unless it names
// a file already), so that the message reads "path: $.json.path: detail".
template <typename F>
auto in_file(const std::string& path, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    throw InputError(e.where().in_file(path), e.detail());
  }
}

nlohmann::json read_json_file(const std::string& path);
proto::WarpSpec read_feature_file(const std::string& path);
std::vector<std::array<double, 2>> read_points_file(const std::string& path);

// Validated problem from a feature file (InputError with the file name in front of the JSON path).
WarpProblem load_problem(const std::string& feature_path);

// The problem of a feature file read already (`path` for messages); `mirror_width` > 0: its features mirrored
// about a texture that wide (the `mirror` option, core/mirror.hpp).
WarpProblem problem_from_spec(const proto::WarpSpec& spec, const std::string& path, int mirror_width = 0);

}  // namespace texwarp::cli
