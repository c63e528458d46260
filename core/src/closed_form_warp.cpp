// The closed form of a trivial warp: see closed_form_warp.hpp.
#include "texwarp/core/closed_form_warp.hpp"

#include <complex>
#include <stdexcept>

#include "texwarp/core/image_buffer.hpp"

namespace texwarp {

std::vector<Point> closed_form_inverse_map_grid(const WarpProblem& problem, int width, int height) {
  if (!has_closed_form(problem)) throw std::logic_error("closed_form_inverse_map_grid: the field is not zero");
  const Similarity inverse = problem.prealignment().inverse();
  std::vector<Point> grid = huge_page_vector<Point>(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    Point* row = grid.data() + static_cast<std::size_t>(y) * width;
    for (int x = 0; x < width; ++x) row[x] = inverse(Point(x + 0.5, y + 0.5));
  }
  return grid;
}

WarpCertificate closed_form_certificate(const WarpProblem& problem, double tolerance_px) {
  if (!has_closed_form(problem)) throw std::logic_error("closed_form_certificate: the field is not zero");
  WarpCertificate c;
  c.exact = true;
  c.tolerance_px = tolerance_px;
  c.min_jacobian_det = 1.0 / std::norm(problem.prealignment().a);
  return c;
}

}  // namespace texwarp
