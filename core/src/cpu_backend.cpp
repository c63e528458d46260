// The CPU reference backend: batches of points integrated in parallel: see cpu_backend.hpp.
#include "texwarp/core/cpu_backend.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "texwarp/core/parallel_chunks.hpp"

namespace texwarp {
namespace {

// Points sharing one step sequence: neighbouring pixels of a row, or consecutive points of a list.
constexpr std::size_t kBatch = 64;

// Runs integrate(begin, end) over batches of the n points on the control's threads, with progress and
// cancellation between batches; the first exception stops the others and is rethrown.
template <typename Integrate>
void for_each_batch(std::size_t n, const RunControl& control, Integrate&& integrate) {
  for_each_chunk(n, kBatch, control, integrate, true);
}

}  // namespace

void CpuBackend::flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                              Direction direction, const RunControl& control) {
  if (points.empty() || problem.segments().at(segment).field_is_zero) {
    if (control.progress) control.progress(1.0);
    return;
  }
  const VelocityField field(problem, segment);
  for_each_batch(points.size(), control, [&](std::size_t begin, std::size_t end) {
    integrate_pathlines(field, points.subspan(begin, end - begin), direction, problem.pathline_tolerance_px(direction));
  });
}

void CpuBackend::flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                            std::span<FlowJacobian> jacobians, Direction direction,
                                            const RunControl& control) {
  if (jacobians.size() != points.size()) throw std::invalid_argument("flow_points_with_jacobian: sizes differ");
  const VelocityField field(problem, segment);
  for_each_batch(points.size(), control, [&](std::size_t begin, std::size_t end) {
    integrate_pathlines(field, points.subspan(begin, end - begin), jacobians.subspan(begin, end - begin), direction,
                        problem.pathline_tolerance_px(direction));
  });
  if (points.empty() && control.progress) control.progress(1.0);
}

}  // namespace texwarp
