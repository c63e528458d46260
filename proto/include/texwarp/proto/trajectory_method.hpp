// TrajectoryMethod: how the planner found the features' trajectories, a wire enum of the report ("trajectory").
#pragma once

#include <array>
#include <utility>

#include "texwarp/proto/enum_names.hpp"

namespace texwarp::proto {

// How the features' trajectories were found: straight lines (the paper's), a repair of them (intermediate
// configurations; also those added to straight lines that pass close, to lower the pair energy), or the sweep that
// keeps any distinct sources and targets apart (core/trajectory_planner.hpp).
enum class TrajectoryMethod { kStraight, kRepaired, kSweep };

template <>
struct EnumNames<TrajectoryMethod> {
  static constexpr std::array<std::pair<TrajectoryMethod, const char*>, 3> kTable = {
      {{TrajectoryMethod::kStraight, "straight"},
       {TrajectoryMethod::kRepaired, "repaired"},
       {TrajectoryMethod::kSweep, "sweep"}}};
};

}  // namespace texwarp::proto
