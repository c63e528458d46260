// The certified lattice inverse map: see certified_warp.hpp.
#include "texwarp/core/certified_warp.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <unordered_map>

#include "texwarp/core/hermite_cell.hpp"
#include "texwarp/core/image_buffer.hpp"
#include "texwarp/core/numerical_error.hpp"

namespace texwarp {
namespace {

// Share of the tolerance left to the pathlines' integration; the rest, to interpolation. Where the pathlines' steps
// are set by the step controller's floor (smooth and clustered sets: ~19 evaluations each at any share, measured
// when every first step was 1/8; smooth sets are now one step, 7, at this share, and a smaller one could make them
// two) a smaller share costs no evaluations and leaves the interpolant more room; where they are set by the tolerance
// (dense independent sets: evaluations go as tolerance^−0.2) a larger one saves evaluations. Issue 15, field
// evaluations in plain-pathline units (a Jacobian pathline's evaluation ≈ 2.47 plain ones) at shares 0.1 / 0.15 / 0.2:
//   - independent 200 at 1024²: 9.66 / 9.05 / 8.80 M; at 512²: 4.18 / 4.00 / 3.89 M;
//   - smooth 200 at 512² and 1024²: 0.47 / 0.48 / 0.50 M and 0.70 / 0.71 / 0.73 M;
//   - clustered 200 at 512² and 1024²: 0.65 / 0.66 / 0.67 M and 0.88 / 0.89 / 0.90 M; independent 50 at 1024²:
//     0.62 / 0.62 / 0.63 M.
// 0.15 takes most of the saving where the time goes and costs the fast sets 0–2 %. Where it would fall below
// kFloatMinTolerancePx (float32's limit, below which the OpenCL kernels run in double, about 2.5× slower), the
// larger share is kept.
constexpr double kIntegrationShare = 0.15;
constexpr double kLargerIntegrationShare = 0.2;
// The check points and the edges' estimates see most, not all, of a cell's interpolation error: a cell's error
// anywhere is taken as at most this many times their worst. Verified against every pixel of several warp families
// (tests/core/certified_warp_test.cpp, CertificateBound): measured ratios 0.98–1.19 there; 1.02–1.23 on 256² and
// 512² warps of 50–200 smooth, clustered and independent features (bench/lattice_profile.cpp --measure), where the
// check points alone had up to 1.64 and one clustered set at 128² broke the bound (0.058 px against 0.050).
constexpr double kCheckMargin = 1.5;
// A cell of size ≥ 4 is first judged without its quarter points: by its centre, its edge midpoints and the edges'
// estimates. Where that estimate is within the threshold by this margin the cell is accepted on it; where it is
// over the threshold the cell fails; only between the two are its quarter points integrated and the cell judged
// on every check point (with kCheckMargin). The quarter points of a failed cell are nodes of what follows (its
// children's centres, or its 2 px grid), so what is saved is those of the cells accepted at once: on independent
// 200 at 1024², when its 8 px cells were such Hermite cells too, 5191 of the 6149 accepted ones, 20764 of 32928 plain
// pathlines at that level. Measured over every pixel of the cells of seven 256²–1024² warps of 50–200 smooth,
// clustered and independent features (exact map at 0.001 px), a cell accepted at once had at most 1.91 times that
// estimate (at 8 px; 1.35 at 16 px and more, where these cells are now: 8 px cells are kPlainMidpointCellPx's).
constexpr double kQuickCheckMargin = 3.0;
// Cells of kPlainMidpointCellPx (the lattice's last level in practice: a failed one goes on to its 2 px grid, not
// split) take their edge midpoints plain: there the midpoints' Jacobians serve the interpolant alone (its twists and
// the edges' estimates), not the children's corners, and they were 17642 of the 19700 Jacobian pathlines of that
// level on independent 200 at 1024². Their twists come instead from the Jacobians of the neighbouring corners,
// 8 px away on either side (central differences), and their checks are the centre, the edge midpoints and the
// quarter points, without the edges' estimates; judged on every check point they take kPlainMidpointCheckMargin.
// Measured over every pixel of the 8 px cells of seven 256²–1024² warps of 50–200 smooth, clustered and independent
// features (exact map at 0.001 px), against the Hermite cells' 6149 such cells held on independent 200 at 1024²:
//   - accepted on the first checks (kQuickCheckMargin): 5074, off by at most 1.71 × that estimate plus the nodes'
//     integration tolerance;
//   - held on every check point: 752 more at margin 1.75 (worst 1.17), 945 at 1.5 (worst 1.49, too close).
constexpr int kPlainMidpointCellPx = 8;
constexpr double kPlainMidpointCheckMargin = 1.75;
// A pathline that carries its Jacobian (the variational equation) costs about this many plain ones on the OpenCL
// backend: 2.6–2.8× with 200 features, 3.0× with 50 in float32 (texwarp_bench_kernels --jacobian, medians of 3–5,
// since the gradient's pair loop sums full rows of z alone; 3.3–3.5× before). When the lattice would cost more
// than a pathline per pixel, the exact path is cheaper and is taken instead.
constexpr double kJacobianCost = 3.0;
// A pathline's field evaluations go about as its tolerance^−kEvaluationExponent (issue 15, independent 200 at
// 1024²: 70.9 / 61.0 / 53.7 per pathline over the whole lattice at integration shares 0.05 / 0.1 / 0.2; the pixels
// of failed cells 58.7 / 52.8 / 48.7 at 0.005 / 0.01 / 0.02 px). Pixels by their own pathline are integrated to a
// looser tolerance than the nodes, and cost that much less than a node's plain pathline.
constexpr double kEvaluationExponent = 0.2;

// A failed cell of kFineCellPx that would keep its pixels' own pathlines gets one more chance first: plain nodes on
// its 2 px grid (25, 9 to 13 of them lattice nodes already) and the tensor-product quartic through them, checked at
// 20 pixels where that interpolant's error peaks (offsets 1 and 7 across the grid lines). Where the map
// changes too fast for a cubic on 8 px it is still smooth on 2 px: on independent 200 at 1024², 86 % of the failed
// 8 px cells were within the threshold at every pixel. Its nodes and check points are pixels of the cell itself
// (but for the 2 px grid's far edges), so a cell that fails again loses little. The checks see most, not all, of
// its error: measured over every pixel of failed cells (independent 200 at 512² and 1024², clustered 200 at 512²),
// the worst interpolated pixel was at most 1.78 times the worst check; kFineCheckMargin covers that.
constexpr int kFineCellPx = 8;
constexpr double kFineCheckMargin = 2.0;
// As with kQuickCheckMargin, a fine cell is first judged on 10 of its checks (the pixels next to its corners and
// its first edges, and two on its middle lines: for_each_fine_first_check). Within a third of the tolerance there
// it is accepted; over the fine threshold it fails; between the two its other 10 checks are integrated. Chosen
// over the failed 8 px cells of seven 256²–1024² warps of 50–200 smooth, clustered and independent features, every
// pixel against the exact map at 0.001 px: a cell accepted at once was off by at most 1.65 times that estimate plus
// the nodes' integration tolerance (with 8 first checks it would have been 2.88, with 4 5.58). Those cells were
// 3645 of the 3959 the 20 checks held; on independent 200 at 1024² this saves 15930 of 68818 pathlines.
constexpr double kFineQuickCheckMargin = 3.0;

// A pixel's own pathline (integrated to pixel_px) in the lattice's plain pathlines (integrated to node_px).
double own_pathline_cost(double node_px, double pixel_px) { return std::pow(node_px / pixel_px, kEvaluationExponent); }

struct Cell {
  int x0;
  int y0;
  int size;
};

bool finite(Point p) { return std::isfinite(p.real()) && std::isfinite(p.imag()); }

// The centre of pixel i of a row-major grid `width` wide.
Point pixel_centre(std::size_t i, int width) {
  const auto w = static_cast<std::size_t>(width);
  const std::size_t row = i / w;
  return {static_cast<double>(i - row * w) + 0.5, static_cast<double>(row) + 0.5};
}

// A backend's pathline end (and Jacobian) at the output pixel centre `at`, refused when not finite: the lattice
// never interpolates from, nor outputs, what is not a number.
void require_finite(Point at, Point value, const FlowJacobian* jacobian = nullptr) {
  if (finite(value) && (jacobian == nullptr || (finite(jacobian->dx) && finite(jacobian->dy)))) return;
  char msg[160];
  std::snprintf(msg, sizeof msg, "the inverse map is not finite at output pixel centre (%.1f, %.1f)", at.real(),
                at.imag());
  throw NumericalError(msg);
}

// Lattice nodes (integer pixel indices; the node stands for the pixel centre) computed so far: every node's
// value, and the Jacobian of those that need one (cell corners and edge midpoints, which shape the
// interpolant). A check point that only measures the interpolant's error gets a plain pathline; if its cell is
// refined and the point becomes a corner, it is integrated again with its Jacobian.
class NodeStore {
 public:
  void request(int x, int y, bool with_jacobian) {
    auto [it, inserted] = index_.try_emplace(key(x, y), Node{});
    Node& node = it->second;
    if (inserted) node.value_slot = nodes_++;
    if (with_jacobian) {
      if (node.jacobian_slot != kNone || node.pending_jacobian) return;
      node.pending_jacobian = true;
      with_jacobian_.push_back({x, y});
    } else if (inserted) {
      plain_.push_back({x, y});
    }
  }

  // Integrates every requested node in two batches (plain, with Jacobian); returns the pathlines' cost in
  // plain pathlines.
  double resolve(WarpBackend& backend, const WarpProblem& problem, const RunControl& control,
                 WarpCertificate& certificate) {
    const double cost = pending_cost();
    values_.resize(nodes_);
    if (!plain_.empty()) {
      std::vector<Point> points = centres(plain_);
      map_points(backend, problem, points, Direction::kInverse, control);
      for (std::size_t k = 0; k < points.size(); ++k) {
        require_finite(centre(plain_[k]), points[k]);
        values_[slot(plain_[k]).value_slot] = points[k];
      }
      certificate.pathlines += points.size();
    }
    if (!with_jacobian_.empty()) {
      std::vector<Point> points = centres(with_jacobian_);
      std::vector<FlowJacobian> jac(points.size());
      map_points_with_jacobian(backend, problem, points, jac, Direction::kInverse, control);
      for (std::size_t k = 0; k < points.size(); ++k) {
        require_finite(centre(with_jacobian_[k]), points[k], &jac[k]);
        Node& node = slot(with_jacobian_[k]);
        values_[node.value_slot] = points[k];
        node.jacobian_slot = jacobians_.size();
        node.pending_jacobian = false;
        jacobians_.push_back(jac[k]);
      }
      certificate.pathlines += points.size();
      certificate.jacobian_pathlines += points.size();
    }
    plain_.clear();
    with_jacobian_.clear();
    return cost;
  }

  // What request(x, y, with_jacobian) would add to pending_cost(), in plain pathlines.
  double request_cost(int x, int y, bool with_jacobian) const {
    const auto it = index_.find(key(x, y));
    if (it == index_.end()) return with_jacobian ? kJacobianCost : 1.0;
    const Node& node = it->second;
    return with_jacobian && node.jacobian_slot == kNone && !node.pending_jacobian ? kJacobianCost : 0.0;
  }

  double pending_cost() const {
    return static_cast<double>(plain_.size()) + kJacobianCost * static_cast<double>(with_jacobian_.size());
  }
  // Resolved nodes only.
  bool known(int x, int y) const {
    const auto it = index_.find(key(x, y));
    return it != index_.end() && it->second.value_slot < values_.size();
  }
  bool has_jacobian(int x, int y) const {
    const auto it = index_.find(key(x, y));
    return it != index_.end() && it->second.jacobian_slot != kNone;
  }
  Point value(int x, int y) const { return values_[index_.at(key(x, y)).value_slot]; }
  const FlowJacobian& jacobian(int x, int y) const { return jacobians_[index_.at(key(x, y)).jacobian_slot]; }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  struct Node {
    std::size_t value_slot = kNone;
    std::size_t jacobian_slot = kNone;
    bool pending_jacobian = false;
  };
  struct Pixel {
    int x;
    int y;
  };

  static long long key(int x, int y) { return (static_cast<long long>(y) << 32) ^ static_cast<unsigned>(x); }
  Node& slot(Pixel p) { return index_.at(key(p.x, p.y)); }
  static Point centre(Pixel p) { return {p.x + 0.5, p.y + 0.5}; }
  static std::vector<Point> centres(const std::vector<Pixel>& pixels) {
    std::vector<Point> points;
    points.reserve(pixels.size());
    for (const Pixel& p : pixels) points.push_back(centre(p));
    return points;
  }

  std::unordered_map<long long, Node> index_;
  std::size_t nodes_ = 0;
  std::vector<Point> values_;
  std::vector<FlowJacobian> jacobians_;
  std::vector<Pixel> plain_;
  std::vector<Pixel> with_jacobian_;
};

bool plain_midpoints(const Cell& c) { return c.size == kPlainMidpointCellPx; }

// The Jacobian nodes a cell of kPlainMidpointCellPx takes its twists from: its corners' neighbours one cell away
// along each axis (those that are not its own corners), f(x, y).
template <typename F>
void for_each_twist_neighbour(const Cell& c, F&& f) {
  const int s = c.size;
  for (const int y : {c.y0, c.y0 + s}) {
    f(c.x0 - s, y);
    f(c.x0 + 2 * s, y);
  }
  for (const int x : {c.x0, c.x0 + s}) {
    f(x, c.y0 - s);
    f(x, c.y0 + 2 * s);
  }
}

// The interpolant of a cell of size ≥ 2 from its corners and its edge midpoints' Jacobians, or for a cell of
// kPlainMidpointCellPx its corners' neighbours' (see there).
HermiteCell make_cell(const NodeStore& nodes, const Cell& c) {
  const int xs[4] = {c.x0, c.x0 + c.size, c.x0, c.x0 + c.size};
  const int ys[4] = {c.y0, c.y0, c.y0 + c.size, c.y0 + c.size};
  Point v[4];
  FlowJacobian j[4];
  for (int k = 0; k < 4; ++k) {
    v[k] = nodes.value(xs[k], ys[k]);
    j[k] = nodes.jacobian(xs[k], ys[k]);
  }
  if (plain_midpoints(c)) {
    // ∂²f/∂u∂v at each corner: the central differences of ∂f/∂u along v and of ∂f/∂v along u, averaged.
    const auto s = static_cast<double>(c.size);
    Point twists[4];
    for (int k = 0; k < 4; ++k) {
      const int x = xs[k], y = ys[k];
      const Point fu_v = 0.5 * s * (nodes.jacobian(x, y + c.size).dx - nodes.jacobian(x, y - c.size).dx);
      const Point fv_u = 0.5 * s * (nodes.jacobian(x + c.size, y).dy - nodes.jacobian(x - c.size, y).dy);
      twists[k] = 0.5 * (fu_v + fv_u);
    }
    return HermiteCell::with_twists(v, j, twists, c.size);
  }
  const int h = c.size / 2;
  const FlowJacobian mid[4] = {nodes.jacobian(c.x0 + h, c.y0), nodes.jacobian(c.x0, c.y0 + h),
                               nodes.jacobian(c.x0 + c.size, c.y0 + h), nodes.jacobian(c.x0 + h, c.y0 + c.size)};
  return HermiteCell(v, j, mid, c.size);
}

// The check points of a cell of size ≥ 2: centre and edge midpoints (the corners of its children), and for
// size ≥ 4 the quarter points (its children's centres). The quarter points matter: the error of the estimated
// twist term vanishes at the centre and on the edges, and peaks near them. f(x, y, with_jacobian): the edge
// midpoints' Jacobians also shape the interpolant (its twists), but in cells of kPlainMidpointCellPx.
// for_each_first_check: the centre and edge midpoints; for_each_quarter_point: the rest (none below 4 px), integrated
// only for cells that need them (see kQuickCheckMargin).
template <typename F>
void for_each_first_check(const Cell& c, F&& f) {
  const int h = c.size / 2;
  const bool j = !plain_midpoints(c);
  f(c.x0 + h, c.y0 + h, false);
  f(c.x0 + h, c.y0, j);
  f(c.x0, c.y0 + h, j);
  f(c.x0 + c.size, c.y0 + h, j);
  f(c.x0 + h, c.y0 + c.size, j);
}
template <typename F>
void for_each_quarter_point(const Cell& c, F&& f) {
  if (c.size < 4) return;
  const int q = c.size / 4;
  f(c.x0 + q, c.y0 + q, false);
  f(c.x0 + 3 * q, c.y0 + q, false);
  f(c.x0 + q, c.y0 + 3 * q, false);
  f(c.x0 + 3 * q, c.y0 + 3 * q, false);
}
template <typename F>
void for_each_check_point(const Cell& c, F&& f) {
  for_each_first_check(c, f);
  for_each_quarter_point(c, f);
}

// The larger of a and b, NaN when either is (std::max(a, NaN) is a): a cell error that is not a number fails.
double max_or_nan(double a, double b) { return a >= b || std::isnan(a) ? a : b; }

// The worst |interpolant − node| over the check points that for_each_points(f) visits.
template <typename G>
double check_error(const NodeStore& nodes, const HermiteCell& cell, const Cell& c, G&& for_each_points) {
  double error = 0.0;
  for_each_points([&](int x, int y, bool) {
    const Point interpolated =
        cell.value(static_cast<double>(x - c.x0) / c.size, static_cast<double>(y - c.y0) / c.size);
    error = max_or_nan(error, std::abs(interpolated - nodes.value(x, y)));
  });
  return error;
}

// A fine cell's nodes (offsets 0, 2, …, 8 on both axes) and check points (offset 1 or 7 on one axis against
// 0, 1, 2, 4, 6, 7 on the other), as pixel indices: its first checks (see kFineQuickCheckMargin) and the others.
template <typename F>
void for_each_fine_node(const Cell& c, F&& f) {
  for (int j = 0; j <= kFineCellPx; j += 2) {
    for (int i = 0; i <= kFineCellPx; i += 2) f(c.x0 + i, c.y0 + j);
  }
}
template <typename F>
void for_each_fine_first_check(const Cell& c, F&& f) {
  for (const auto& [u, v] : {std::pair{1, 0}, {7, 0}, {0, 1}, {0, 7}, {1, 1}, {7, 1}, {1, 7}, {7, 7}, {1, 4}, {4, 1}}) {
    f(c.x0 + u, c.y0 + v);
  }
}
template <typename F>
void for_each_fine_other_check(const Cell& c, F&& f) {
  for (const auto& [u, v] : {std::pair{1, 2}, {1, 6}, {7, 2}, {7, 4}, {7, 6}, {2, 1}, {6, 1}, {2, 7}, {4, 7}, {6, 7}}) {
    f(c.x0 + u, c.y0 + v);
  }
}

// The tensor-product quartic through a fine cell's 5×5 nodes, at pixel offsets (u, v) from its first node.
class FineCell {
 public:
  FineCell(const NodeStore& nodes, const Cell& c) {
    for (int j = 0; j < 5; ++j) {
      for (int i = 0; i < 5; ++i) node_[j][i] = nodes.value(c.x0 + 2 * i, c.y0 + 2 * j);
    }
  }
  // The value, and the map's Jacobian (its columns: ∂/∂u, ∂/∂v).
  Point value(double u, double v, FlowJacobian& j) const {
    double bu[5], du[5], bv[5], dv[5];
    basis(u, bu, du);
    basis(v, bv, dv);
    Point out = 0.0, ou = 0.0, ov = 0.0;
    for (int r = 0; r < 5; ++r) {
      for (int i = 0; i < 5; ++i) {
        out += bv[r] * bu[i] * node_[r][i];
        ou += bv[r] * du[i] * node_[r][i];
        ov += dv[r] * bu[i] * node_[r][i];
      }
    }
    j = FlowJacobian{ou, ov};
    return out;
  }

 private:
  // Lagrange's basis on the nodes 0, 2, 4, 6, 8 and its derivative, at u.
  static void basis(double u, double* b, double* d) {
    for (int k = 0; k < 5; ++k) {
      double value = 1.0, slope = 0.0;
      for (int m = 0; m < 5; ++m) {
        if (m == k) continue;
        const double f = (u - 2.0 * m) / (2.0 * (k - m));
        slope = slope * f + value / (2.0 * (k - m));
        value *= f;
      }
      b[k] = value;
      d[k] = slope;
    }
  }
  Point node_[5][5];
};

// The error of a cell's interpolant along one edge (a cubic Hermite of the end points' values f0, f1 and
// derivatives d0, d1 along it, in the cell's parameter), estimated from the edge midpoint's value fm and
// derivative dm: the quintic through all three differs from the cubic by 16·v²(1 − v)²·(E + E'·(v − ½)), E and E'
// the cubic's errors in value and derivative at the midpoint; its largest modulus at the edge's pixels. The
// midpoint alone sees the edge's error where it is symmetric; near features it is not, and peaks off the middle
// (issue 15: 1.5–1.6 times the midpoint's on the worst edges), where E' shows it, at no pathline's cost.
double edge_error_estimate(Point f0, Point d0, Point f1, Point d1, Point fm, Point dm, int size) {
  const Point e = fm - (0.5 * (f0 + f1) + 0.125 * (d0 - d1));
  const Point e1 = dm - (1.5 * (f1 - f0) - 0.25 * (d0 + d1));
  double worst = 0.0;
  for (int k = 1; k < size; ++k) {
    const double v = static_cast<double>(k) / size;
    const double w = v * v * (1.0 - v) * (1.0 - v);
    worst = max_or_nan(worst, 16.0 * w * std::abs(e + (v - 0.5) * e1));
  }
  return worst;
}

// The largest of the four edges' estimates of a cell of size ≥ 2 (edge_error_estimate; its midpoints carry
// Jacobians).
double edges_error_estimate(const NodeStore& nodes, const Cell& c) {
  const int s = c.size;
  const int h = s / 2;
  const auto ds = static_cast<double>(s);
  auto along_x = [&](int x, int y) { return ds * nodes.jacobian(x, y).dx; };
  auto along_y = [&](int x, int y) { return ds * nodes.jacobian(x, y).dy; };
  const int x0 = c.x0, y0 = c.y0, x1 = c.x0 + s, y1 = c.y0 + s;
  double worst = 0.0;
  for (const int y : {y0, y1}) {  // bottom and top
    worst = max_or_nan(worst, edge_error_estimate(nodes.value(x0, y), along_x(x0, y), nodes.value(x1, y),
                                                  along_x(x1, y), nodes.value(x0 + h, y), along_x(x0 + h, y), s));
  }
  for (const int x : {x0, x1}) {  // left and right
    worst = max_or_nan(worst, edge_error_estimate(nodes.value(x, y0), along_y(x, y0), nodes.value(x, y1),
                                                  along_y(x, y1), nodes.value(x, y0 + h), along_y(x, y0 + h), s));
  }
  return worst;
}

// What a failed cell costs from here on, in plain pathlines, when its children are accepted with probability
// `accept`: the cheaper of its pixels' own pathlines (all but about 8 are not nodes yet; each costs `own` plain
// ones) and a split (about 13 new Jacobian nodes and, for children of ≥ 4 px, 16 plain check points) with each
// child failing in turn.
double failed_cell_cost(int size, double accept, double own) {
  if (size <= 2) return 0.0;  // a 2 px cell's pixels are all nodes already
  const int h = size / 2;
  const double split =
      13.0 * kJacobianCost + (h >= 4 ? 16.0 : 0.0) + 4.0 * (1.0 - accept) * failed_cell_cost(h, accept, own);
  return std::min((static_cast<double>(size) * size - 8.0) * own, split);
}

// The children of a cell of size ≥ 4 (those that start inside the image).
std::vector<Cell> children_of(const Cell& c, int width, int height) {
  const int h = c.size / 2;
  std::vector<Cell> out;
  for (const auto& [dx, dy] : {std::pair{0, 0}, std::pair{h, 0}, std::pair{0, h}, std::pair{h, h}}) {
    if (c.x0 + dx < width && c.y0 + dy < height) out.push_back({c.x0 + dx, c.y0 + dy, h});
  }
  return out;
}

// The nodes a cell needs first: its corners and edge midpoints with their Jacobians (a cell of
// kPlainMidpointCellPx: its midpoints plain, its corners' neighbours with theirs), its centre plain (its quarter
// points only where for_each_first_check does not settle it).
template <typename F>
void for_each_first_node(const Cell& c, F&& f) {
  f(c.x0, c.y0, true);
  if (c.size == 1) return;
  f(c.x0 + c.size, c.y0, true);
  f(c.x0, c.y0 + c.size, true);
  f(c.x0 + c.size, c.y0 + c.size, true);
  for_each_first_check(c, f);
  if (plain_midpoints(c)) for_each_twist_neighbour(c, [&](int x, int y) { f(x, y, true); });
}
// Every node a cell may need: those and its quarter points (plain).
template <typename F>
void for_each_node(const Cell& c, F&& f) {
  for_each_first_node(c, f);
  for_each_quarter_point(c, f);
}

// The pixels of a cell that are not resolved nodes.
double unknown_pixels(const NodeStore& nodes, const Cell& c, int width, int height) {
  double count = 0.0;
  for (int y = c.y0; y < std::min(c.y0 + c.size, height); ++y) {
    for (int x = c.x0; x < std::min(c.x0 + c.size, width); ++x) count += nodes.known(x, y) ? 0.0 : 1.0;
  }
  return count;
}

// A failed cell of size ≥ 4: split it, or give its pixels their own pathlines (`own` plain ones each)? Split when
// the new nodes its children need (counted exactly, each once) plus the expected cost of the children that fail in
// turn (at acceptance rate `accept`) cost less than the pathlines of its pixels that are not nodes yet.
bool split_pays(const NodeStore& nodes, const Cell& c, int width, int height, double accept, double own) {
  const double pixels = own * unknown_pixels(nodes, c, width, height);
  std::vector<std::pair<int, int>> counted;
  double split = 0.0;
  for (const Cell& child : children_of(c, width, height)) {
    for_each_node(child, [&](int x, int y, bool with_jacobian) {
      const std::pair<int, int> at{x, y};
      if (std::find(counted.begin(), counted.end(), at) != counted.end()) return;
      counted.push_back(at);
      split += nodes.request_cost(x, y, with_jacobian);
    });
    split += (1.0 - accept) * failed_cell_cost(child.size, accept, own);
  }
  return split < pixels;
}

// The problem as the lattice integrates it: its own trajectories (planned once, by its constructor), to the
// integration's share of the tolerance.
WarpProblem integration_problem(const WarpProblem& problem, double tolerance_px) {
  const double share =
      kIntegrationShare * tolerance_px >= kFloatMinTolerancePx ? kIntegrationShare : kLargerIntegrationShare;
  // Never below what a problem accepts: a lattice asked for less than that fails every cell and takes the exact path.
  return problem.with_tolerance(std::max(kMinTolerancePx, std::min(problem.tolerance_px(), share * tolerance_px)));
}

// The problem as a pixel's own pathline integrates it (every pixel on the exact path; the pixels of failed cells
// not split): to the lattice's tolerance, or the problem's own where that is tighter. Such a pixel's error is its
// integration error alone, with no interpolation to share the tolerance with.
WarpProblem pixel_problem(const WarpProblem& problem, double tolerance_px) {
  return problem.with_tolerance(std::max(kMinTolerancePx, std::min(problem.tolerance_px(), tolerance_px)));
}

// Random distinct output pixels, seeded.
std::vector<std::size_t> sample_pixels(int width, int height, std::size_t count, std::uint32_t seed) {
  const std::size_t total = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<std::size_t> out;
  if (count >= total) {
    out.resize(total);
    for (std::size_t i = 0; i < total; ++i) out[i] = i;
    return out;
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, total - 1);
  std::unordered_map<std::size_t, bool> seen;
  while (out.size() < count) {
    const std::size_t i = pick(rng);
    if (seen.emplace(i, true).second) out.push_back(i);
  }
  return out;
}

RunControl without_progress(const RunControl& control) {
  RunControl c = control;
  c.progress = nullptr;
  return c;
}

}  // namespace

std::vector<Point> certified_inverse_map_grid(WarpBackend& backend, const WarpProblem& problem, int width, int height,
                                              const CertifiedGridOptions& options, const RunControl& control,
                                              WarpCertificate& certificate) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("certified_inverse_map_grid: empty grid");
  if (!(options.tolerance_px > 0.0)) throw std::invalid_argument("certified_inverse_map_grid: tolerance must be > 0");
  int s0 = 1;
  while (s0 * 2 <= std::max(1, options.initial_cell_px)) s0 *= 2;

  const WarpProblem integrated = integration_problem(problem, options.tolerance_px);
  const RunControl inner = without_progress(control);
  const double integration_px = integrated.tolerance_px();
  // Pixels of failed cells, each by its own pathline: as on the exact path (their error is that alone).
  const WarpProblem by_own_pathline = pixel_problem(problem, options.tolerance_px);
  const double own_cost = own_pathline_cost(integration_px, by_own_pathline.tolerance_px());
  // A cell is accepted when its margin (kCheckMargin and the others) × its worst check point error and the nodes'
  // integration error fit in the tolerance; interpolation_bound: the largest margin × error of the accepted cells.
  const double room = options.tolerance_px - integration_px;
  const double quick_threshold = room / kQuickCheckMargin;
  auto full_margin = [](const Cell& c) { return plain_midpoints(c) ? kPlainMidpointCheckMargin : kCheckMargin; };
  double interpolation_bound = 0.0;

  certificate = WarpCertificate{};
  certificate.tolerance_px = options.tolerance_px;
  certificate.min_jacobian_det = std::numeric_limits<double>::infinity();
  certificate.smallest_cell_px = s0;

  std::vector<Point> grid = huge_page_vector<Point>(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  NodeStore nodes;
  std::vector<Cell> active;
  for (int y = 0; y < height; y += s0) {
    for (int x = 0; x < width; x += s0) active.push_back({x, y, s0});
  }
  auto pixels_of = [&](const Cell& c) {
    return static_cast<double>(std::min(c.x0 + c.size, width) - c.x0) * (std::min(c.y0 + c.size, height) - c.y0);
  };
  const auto total_pixels = static_cast<double>(grid.size());
  double accepted_pixels = 0.0;
  double spent = 0.0;               // the lattice's pathlines so far, in plain pathlines
  std::vector<Cell> by_pathline;    // rejected cells not split: their pixels' own pathlines
  double previous_fail_rate = 0.0;  // none yet
  double pixels_pending = 0.0;      // what the cells in by_pathline will cost, in plain pathlines
  if (options.profile) *options.profile = LatticeProfile{};

  while (!active.empty()) {
    if (control.canceled()) throw CanceledError();
    LatticeLevel level;
    level.cell_px = active.front().size;
    level.cells = active.size();
    // A single pixel is the node itself, its value and Jacobian.
    for (const Cell& c : active) for_each_first_node(c, [&](int x, int y, bool j) { nodes.request(x, y, j); });
    if (spent + nodes.pending_cost() + pixels_pending > own_cost * total_pixels) {
      // The map varies too fast for the lattice to pay: a pathline per pixel.
      if (options.profile) options.profile->exact = true;
      // Its pathlines meet the lattice's tolerance too, where that is tighter than the problem's own.
      const WarpProblem exact_problem = pixel_problem(problem, options.tolerance_px);
      std::vector<Point> exact = backend.inverse_map_grid(exact_problem, width, height, control);
      certificate = exact_grid_certificate(backend, exact_problem, width, height, options, control);
      return exact;
    }
    const std::size_t pathlines_before = certificate.pathlines;
    const std::size_t jacobian_before = certificate.jacobian_pathlines;
    const auto resolve_start = std::chrono::steady_clock::now();
    spent += nodes.resolve(backend, integrated, inner, certificate);

    // Every cell's first estimate (see kQuickCheckMargin); those it does not settle get their quarter points, in
    // a second batch.
    std::vector<std::optional<HermiteCell>> cells(active.size());  // none for a single pixel: the node itself
    std::vector<double> errors(active.size(), 0.0);
    std::vector<bool> quarters(active.size(), false);  // judged on every check point
    for (std::size_t k = 0; k < active.size(); ++k) {
      const Cell& c = active[k];
      if (c.size < 2) continue;
      cells[k] = make_cell(nodes, c);
      errors[k] = check_error(nodes, *cells[k], c, [&](auto&& f) { for_each_first_check(c, f); });
      if (!plain_midpoints(c)) errors[k] = max_or_nan(errors[k], edges_error_estimate(nodes, c));
      if (c.size >= 4 && errors[k] > quick_threshold && errors[k] <= room / full_margin(c)) {
        quarters[k] = true;
        ++level.quarter_checked;
        for_each_quarter_point(c, [&](int x, int y, bool) { nodes.request(x, y, false); });
      }
    }
    spent += nodes.resolve(backend, integrated, inner, certificate);
    level.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - resolve_start).count();
    level.jacobian_pathlines = certificate.jacobian_pathlines - jacobian_before;
    level.plain_pathlines = certificate.pathlines - pathlines_before - level.jacobian_pathlines;

    std::vector<Cell> rejected;
    std::vector<bool> rejected_for_fold;  // per rejected cell: its interpolant folded (its error was within bounds)
    for (std::size_t k = 0; k < active.size(); ++k) {
      const Cell& c = active[k];
      const std::optional<HermiteCell>& cell = cells[k];
      double error = errors[k];
      // Accepted at once, or on every check point (the quarter points'), or (below 4 px, where there are none)
      // on its first checks.
      const bool quick = c.size >= 4 && !quarters[k];
      if (quarters[k]) {
        error = max_or_nan(error, check_error(nodes, *cell, c, [&](auto&& f) { for_each_quarter_point(c, f); }));
      }
      const double margin = quick ? kQuickCheckMargin : full_margin(c);
      bool accept = error <= room / margin;  // NaN never passes
      if (!accept) ++level.failed_error;
      // Fill the cell's pixels from the interpolant; a fold it would introduce sends the cell to refinement.
      double cell_min_det = std::numeric_limits<double>::infinity();
      std::size_t cell_nonpositive = 0;
      const int x_end = std::min(c.x0 + c.size, width);
      const int y_end = std::min(c.y0 + c.size, height);
      for (int y = c.y0; accept && y < y_end; ++y) {
        for (int x = c.x0; x < x_end; ++x) {
          FlowJacobian j;
          Point value;
          if (!cell) {
            value = nodes.value(x, y);  // a node: the pathline itself
            j = nodes.jacobian(x, y);
          } else {
            value = cell->value(static_cast<double>(x - c.x0) / c.size, static_cast<double>(y - c.y0) / c.size, j);
          }
          const double det = j.det();
          if (!(det > 0.0)) {
            if (c.size > 1) {
              accept = false;
              ++level.failed_fold;
              break;
            }
            ++cell_nonpositive;  // the exact map's own (never introduced by interpolation)
          }
          cell_min_det = std::min(cell_min_det, det);
          grid[static_cast<std::size_t>(y) * width + x] = value;
        }
      }
      if (accept) {
        if (quick) ++level.quick_accepted;
        ++certificate.cells;
        certificate.max_error_px_estimated = std::max(certificate.max_error_px_estimated, error);
        interpolation_bound = std::max(interpolation_bound, margin * error);
        certificate.min_jacobian_det = std::min(certificate.min_jacobian_det, cell_min_det);
        certificate.nonpositive_jacobians += cell_nonpositive;
        certificate.smallest_cell_px = std::min(certificate.smallest_cell_px, c.size);
        accepted_pixels += pixels_of(c);
      } else {
        rejected.push_back(c);
        rejected_for_fold.push_back(error <= room / margin);
      }
    }

    // A rejected cell is split in four when that is expected to cost less than its pixels' own pathlines (see
    // split_pays) or when it was rejected for a fold; otherwise, and always at 2 px (all its pixels are nodes already),
    // its pixels keep their own pathlines. Smaller cells fail less often, at a rate that changes from level to level
    // about geometrically: once it has started to fall, the children's failure rate is extrapolated from this level's
    // and the previous one's; before that (at the first level, or while every cell larger than the features' spacing
    // fails) children are assumed accepted, so cells split whenever that can pay. Nodes are requested as cells
    // split, so that a node two of them share is counted once.
    const double fail_rate = static_cast<double>(rejected.size()) / static_cast<double>(active.size());
    const double accept_rate = fail_rate < previous_fail_rate ? 1.0 - fail_rate * fail_rate / previous_fail_rate : 1.0;
    previous_fail_rate = fail_rate;
    std::vector<Cell> next;
    for (std::size_t r = 0; r < rejected.size(); ++r) {
      const Cell& c = rejected[r];
      // A cell that may hold a fold is split down to 2 px, whatever it costs: there its pixels are nodes, 3 of 4
      // with their Jacobian, so the certificate's min det J sees the fold (a larger cell sent to pixels has det J
      // measured only at its few Jacobian nodes).
      const bool split =
          c.size >= 4 && (rejected_for_fold[r] || split_pays(nodes, c, width, height, accept_rate, own_cost));
      if (!split) {
        by_pathline.push_back(c);
        pixels_pending += own_cost * unknown_pixels(nodes, c, width, height);
        ++level.to_pixels;
        continue;
      }
      ++level.split;
      for (const Cell& child : children_of(c, width, height)) {
        for_each_first_node(child, [&](int x, int y, bool j) { nodes.request(x, y, j); });
        next.push_back(child);
      }
    }
    if (options.profile) options.profile->levels.push_back(level);
    active = std::move(next);
    if (control.progress) control.progress(0.9 * accepted_pixels / total_pixels);
  }

  // Failed cells of kFineCellPx bound for their pixels' own pathlines: the quartic on their 2 px grid first (see
  // kFineCheckMargin), where the grid lies inside the image; those it does not hold go on to their pixels.
  const double fine_threshold = room / kFineCheckMargin;
  const double fine_quick_threshold = room / kFineQuickCheckMargin;
  double progress_so_far = 0.0;  // reported before the pixels' batch
  {
    std::vector<Cell> fine;
    std::vector<Cell> rest;
    for (const Cell& c : by_pathline) {
      const bool inside = c.x0 + kFineCellPx < width && c.y0 + kFineCellPx < height;
      (c.size == kFineCellPx && inside ? fine : rest).push_back(c);
    }
    if (!fine.empty()) {
      if (control.canceled()) throw CanceledError();
      const auto fine_start = std::chrono::steady_clock::now();
      const std::size_t pathlines_before = certificate.pathlines;
      for (const Cell& c : fine) {
        for_each_fine_node(c, [&](int x, int y) { nodes.request(x, y, false); });
        for_each_fine_first_check(c, [&](int x, int y) { nodes.request(x, y, false); });
      }
      // Progress through this batch from where the cells left it, half way to the pixels' end (0.95).
      RunControl fine_control = inner;
      const double from = 0.9 * accepted_pixels / total_pixels;
      progress_so_far = from + 0.5 * (0.95 - from);
      if (control.progress) {
        fine_control.progress = [&control, from, end = progress_so_far](double f) {
          control.progress(from + (end - from) * f);
        };
      }
      nodes.resolve(backend, integrated, fine_control, certificate);
      auto fine_error = [&](const FineCell& cell, const Cell& c, auto&& for_each_points) {
        double error = 0.0;
        for_each_points(c, [&](int x, int y) {
          FlowJacobian j;
          error = max_or_nan(error, std::abs(cell.value(x - c.x0, y - c.y0, j) - nodes.value(x, y)));
        });
        return error;
      };
      // First estimates; the cells they do not settle get their other checks, in a second batch.
      std::vector<FineCell> cells;
      std::vector<double> errors;
      std::vector<bool> others;  // judged on every check
      cells.reserve(fine.size());
      for (const Cell& c : fine) {
        cells.emplace_back(nodes, c);
        errors.push_back(
            fine_error(cells.back(), c, [](const Cell& cc, auto&& f) { for_each_fine_first_check(cc, f); }));
        others.push_back(errors.back() > fine_quick_threshold && errors.back() <= fine_threshold);
        if (others.back()) for_each_fine_other_check(c, [&](int x, int y) { nodes.request(x, y, false); });
      }
      nodes.resolve(backend, integrated, inner, certificate);
      std::size_t accepted = 0, quick_accepted = 0;
      for (std::size_t k = 0; k < fine.size(); ++k) {
        const Cell& c = fine[k];
        const FineCell& cell = cells[k];
        double error = errors[k];
        if (others[k]) {
          error = max_or_nan(error,
                             fine_error(cell, c, [](const Cell& cc, auto&& f) { for_each_fine_other_check(cc, f); }));
        }
        const bool quick = !others[k];
        bool accept = error <= (quick ? fine_quick_threshold : fine_threshold);  // NaN never passes
        double cell_min_det = std::numeric_limits<double>::infinity();
        for (int y = c.y0; accept && y < c.y0 + kFineCellPx; ++y) {
          for (int x = c.x0; x < c.x0 + kFineCellPx; ++x) {
            FlowJacobian j;
            const bool node = nodes.known(x, y);
            const Point value = node ? nodes.value(x, y) : cell.value(x - c.x0, y - c.y0, j);
            if (!node) {
              const double det = j.det();
              if (!(det > 0.0)) {
                accept = false;  // a fold the interpolant would introduce: the pixels' own pathlines instead
                break;
              }
              cell_min_det = std::min(cell_min_det, det);
            }
            grid[static_cast<std::size_t>(y) * width + x] = value;
          }
        }
        if (!accept) {
          rest.push_back(c);
          continue;
        }
        ++accepted;
        if (quick) ++quick_accepted;
        ++certificate.cells;
        interpolation_bound = std::max(interpolation_bound, (quick ? kFineQuickCheckMargin : kFineCheckMargin) * error);
        certificate.max_error_px_estimated = std::max(certificate.max_error_px_estimated, error);
        certificate.min_jacobian_det = std::min(certificate.min_jacobian_det, cell_min_det);
        accepted_pixels += pixels_of(c);
      }
      if (options.profile) {
        options.profile->fine_cells = fine.size();
        options.profile->fine_accepted = accepted;
        options.profile->fine_quick_accepted = quick_accepted;
        options.profile->fine_pathlines = certificate.pathlines - pathlines_before;
        options.profile->fine_seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - fine_start).count();
      }
      by_pathline = std::move(rest);
    }
  }

  // Failed cells not split: every pixel by its own pathline (those that are nodes already, from their node), in
  // one batch, in which a work-item's points are neighbours. These cells failed on error, not on a fold (cells
  // that folded were split to 2 px); det J is measured at their Jacobian nodes.
  if (!by_pathline.empty()) {
    std::vector<std::size_t> where;
    std::vector<Point> points;
    for (const Cell& c : by_pathline) {
      const int x_end = std::min(c.x0 + c.size, width);
      const int y_end = std::min(c.y0 + c.size, height);
      for (int y = c.y0; y < y_end; ++y) {
        for (int x = c.x0; x < x_end; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * width + x;
          ++certificate.pixel_pathlines;
          if (nodes.known(x, y)) {
            grid[i] = nodes.value(x, y);
          } else {
            where.push_back(i);
            points.emplace_back(x + 0.5, y + 0.5);
          }
          if (nodes.has_jacobian(x, y)) {
            const double det = nodes.jacobian(x, y).det();
            certificate.min_jacobian_det = std::min(certificate.min_jacobian_det, det);
            if (!(det > 0.0)) ++certificate.nonpositive_jacobians;
          }
        }
      }
    }
    if (control.canceled()) throw CanceledError();
    const auto pixels_start = std::chrono::steady_clock::now();
    // Progress through this batch (often the lattice's largest) from where the cells left it to 0.95.
    RunControl pixels_control = inner;
    if (control.progress) {
      const double from = std::max(progress_so_far, 0.9 * accepted_pixels / total_pixels);
      pixels_control.progress = [&control, from](double f) { control.progress(from + (0.95 - from) * f); };
    }
    map_points(backend, by_own_pathline, points, Direction::kInverse, pixels_control);
    if (options.profile) {
      options.profile->pixel_pathlines = points.size();
      options.profile->pixel_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - pixels_start).count();
    }
    for (std::size_t k = 0; k < points.size(); ++k) {
      require_finite(pixel_centre(where[k], width), points[k]);
      grid[where[k]] = points[k];
    }
    certificate.pathlines += points.size();
    certificate.smallest_cell_px = 1;
  }
  // Interpolated pixels: their cells' margin × worst check point error, plus their nodes' integration error; pixels
  // by their own pathline: their integration tolerance.
  certificate.max_error_px_bound = interpolation_bound + integration_px;
  if (certificate.pixel_pathlines > 0) {
    certificate.max_error_px_bound = std::max(certificate.max_error_px_bound, by_own_pathline.tolerance_px());
  }
  if (control.progress) control.progress(0.95);

  // Independent evidence: random pixels by their own pathline, compared with what the lattice gave them.
  const std::vector<std::size_t> picks = sample_pixels(width, height, options.samples, options.seed);
  std::vector<Point> exact;
  exact.reserve(picks.size());
  for (const std::size_t i : picks) exact.push_back(pixel_centre(i, width));
  const auto sample_start = std::chrono::steady_clock::now();
  map_points(backend, integrated, exact, Direction::kInverse, inner);
  if (options.profile) {
    options.profile->sample_pathlines = exact.size();
    options.profile->sample_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - sample_start).count();
  }
  certificate.pathlines += exact.size();
  certificate.sampled_pixels = exact.size();
  for (std::size_t k = 0; k < picks.size(); ++k) {
    require_finite(pixel_centre(picks[k], width), exact[k]);
    certificate.max_error_px_sampled = std::max(certificate.max_error_px_sampled, std::abs(exact[k] - grid[picks[k]]));
  }
  if (control.progress) control.progress(1.0);
  return grid;
}

WarpCertificate exact_grid_certificate(WarpBackend& backend, const WarpProblem& problem, int width, int height,
                                       const CertifiedGridOptions& options, const RunControl& control) {
  WarpCertificate c;
  c.exact = true;
  c.tolerance_px = problem.tolerance_px();
  c.max_error_px_bound = problem.tolerance_px();  // the pathlines' integration tolerance
  c.pathlines = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const std::vector<std::size_t> picks = sample_pixels(width, height, options.samples, options.seed);
  std::vector<Point> points;
  points.reserve(picks.size());
  for (const std::size_t i : picks) points.push_back(pixel_centre(i, width));
  std::vector<FlowJacobian> jac(points.size());
  map_points_with_jacobian(backend, problem, points, jac, Direction::kInverse, without_progress(control));
  c.pathlines += points.size();
  c.jacobian_pathlines = points.size();
  c.sampled_pixels = points.size();
  c.min_jacobian_det = std::numeric_limits<double>::infinity();
  for (const FlowJacobian& j : jac) {
    const double det = j.det();
    c.min_jacobian_det = std::min(c.min_jacobian_det, det);
    if (!(det > 0.0)) ++c.nonpositive_jacobians;
  }
  return c;
}

}  // namespace texwarp
