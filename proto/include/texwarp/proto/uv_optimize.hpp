// What a mesh job does with its UVs after the warp made them flip-free: lower their stretch by an
// injectivity-preserving optimisation with the pins fixed (core/mesh/uv_optimization.hpp), or keep the warp's.
#pragma once

#include <array>
#include <utility>

#include "texwarp/proto/enum_names.hpp"

namespace texwarp::proto {

enum class UvOptimize { kStretch, kNone };

template <>
struct EnumNames<UvOptimize> {
  static constexpr std::array<std::pair<UvOptimize, const char*>, 2> kTable = {
      {{UvOptimize::kStretch, "stretch"}, {UvOptimize::kNone, "none"}}};
};

}  // namespace texwarp::proto
