// The report's account of a warp's sampling (proto::SamplingReport): the role the source was filtered as, its colour
// space or normal convention, the filter, and what the sampling stage counted.
#pragma once

#include "texwarp/core/image_warp.hpp"
#include "texwarp/proto/job_report.hpp"

namespace texwarp {

proto::SamplingReport sampling_report(const ImageWarpOptions& options, const ResampleStats& stats);

// "color (sRGB), footprint filter: 1234 px averaged over their footprints": the CLI summary's words.
std::string describe_sampling(const proto::SamplingReport& report);

}  // namespace texwarp
