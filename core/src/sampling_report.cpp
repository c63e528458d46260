// The report's account of a warp's sampling: see sampling_report.hpp.
#include "texwarp/core/sampling_report.hpp"

namespace texwarp {

proto::SamplingReport sampling_report(const ImageWarpOptions& options, const ResampleStats& stats) {
  proto::SamplingReport r;
  r.role = options.encoding.role;
  if (r.role == ImageRole::kColor) r.color_space = options.encoding.color_space;
  if (r.role == ImageRole::kNormal) r.normal_convention = options.encoding.normal_convention;
  r.filter = options.filter;
  r.footprint_pixels = stats.footprint_pixels;
  r.pyramid_levels = stats.pyramid_levels;
  r.repaired_normals = stats.repaired_normals;
  return r;
}

std::string describe_sampling(const proto::SamplingReport& report) {
  std::string out = proto::to_string(report.role);
  if (report.color_space) out += " (" + *report.color_space + ")";
  if (report.normal_convention) out += std::string(" (") + proto::to_string(*report.normal_convention) + ")";
  out += std::string(", ") + proto::to_string(report.filter) + " filter";
  if (report.filter == proto::SamplingFilter::kFootprint) {
    out += ": " + std::to_string(report.footprint_pixels) + " px averaged over their footprints";
  }
  if (report.repaired_normals > 0) {
    out +=
        "; " + std::to_string(report.repaired_normals) + " invalid normals repaired (zero length or below the surface)";
  }
  return out;
}

}  // namespace texwarp
