// JSON codec for WarpSpec and point lists. Decoding is strict: unknown keys, wrong types, non-finite numbers,
// out-of-range values and half-given frames are InputErrors naming the JSON path of the offender.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/proto/json_path.hpp"
#include "texwarp/proto/warp_spec.hpp"

namespace texwarp::proto {

// `path` is the JSON path of `value` in its document ("$" for a whole file).
WarpSpec decode_warp_spec(const nlohmann::json& value, const JsonPath& path = {});
nlohmann::json encode_warp_spec(const WarpSpec& spec);

// A frame {"angle_deg", "scale" > 0}, both optional (0° and 1); shared by every feature file that has frames.
FrameSpec decode_frame_spec(const nlohmann::json& value, const JsonPath& path);
nlohmann::json encode_frame_spec(const FrameSpec& frame);

// A list of points [[x, y], ...] (the CLI's points file and its output).
std::vector<std::array<double, 2>> decode_points(const nlohmann::json& value, const JsonPath& path = {});
nlohmann::json encode_points(const std::vector<std::array<double, 2>>& points);

}  // namespace texwarp::proto
