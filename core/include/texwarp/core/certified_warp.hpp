// Certified fast inverse map of an output pixel grid: pathlines (with their Jacobians) only at the nodes of an
// adaptive lattice, cubic Hermite interpolation between them, cells refined until the interpolant meets the
// tolerance at every check point and keeps det J > 0 at every pixel; a certificate says what was shown.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

struct WarpCertificate {
  bool exact = false;         // every pixel by its own pathline
  double tolerance_px = 0.0;  // what the warp was asked to meet
  // max |interpolant − pathline| at the check points of accepted cells (the 2 px grid's too), and of the edges'
  // error estimates
  double max_error_px_estimated = 0.0;
  double max_error_px_sampled = 0.0;  // max over random output pixels mapped by their own pathline
  // Bound on |computed − exact f⁻¹| at every output pixel: the lattice's interpolation error (a margin times the
  // estimates: 1.5 for the Hermite cells judged on every check point (1.75 for the 8 px cells, whose twists come from
  // their corners' neighbours), 3 for those accepted on their centre, edge midpoints and edges alone, 2 for the
  // failed 8 px cells on their 2 px grid, 3 for those accepted on 10 of their 20 checks)
  // plus the nodes' integration tolerance, or where larger the integration tolerance of the pixels that took their own
  // pathline; exact: the integration tolerance.
  double max_error_px_bound = 0.0;
  std::size_t sampled_pixels = 0;
  // min det of the inverse map over every interpolated pixel and every Jacobian node (exact: the sample)
  double min_jacobian_det = 0.0;
  std::size_t nonpositive_jacobians = 0;
  std::size_t pathlines = 0;  // pathlines integrated: lattice nodes, check points and samples
  // of which carried their Jacobian: lattice corners and the edge midpoints of cells larger than 8 px (8 px cells
  // take their twists from their corners' neighbours)
  std::size_t jacobian_pathlines = 0;
  std::size_t cells = 0;            // accepted lattice cells (0 for exact)
  std::size_t pixel_pathlines = 0;  // pixels of failed cells not split, each by its own pathline
  int smallest_cell_px = 0;
};

// Where the lattice's work went, level by level (benchmarks and profiling; not part of the certificate).
struct LatticeLevel {
  int cell_px = 0;                     // the level's cell size
  std::size_t cells = 0;               // cells checked
  std::size_t failed_error = 0;        // of which failed the tolerance at a check point
  std::size_t failed_fold = 0;         // of which the interpolant folded (det J ≤ 0 at a pixel)
  std::size_t split = 0;               // failed cells split in four
  std::size_t to_pixels = 0;           // failed cells whose pixels keep their own pathlines
  std::size_t quick_accepted = 0;      // cells accepted on their first checks (no quarter points; see the bound)
  std::size_t quarter_checked = 0;     // cells those did not settle: judged on their quarter points too
  std::size_t plain_pathlines = 0;     // integrated for this level: check points
  std::size_t jacobian_pathlines = 0;  // corners and edge midpoints (8 px: corners' neighbours), with Jacobians
  double seconds = 0.0;                // wall time of those pathlines
};
struct LatticeProfile {
  std::vector<LatticeLevel> levels;
  bool exact = false;  // the lattice would not pay: every pixel by its own pathline
  // failed 8 px cells given the quartic on their 2 px grid before their pixels' own pathlines: checked, accepted,
  // the pathlines of their nodes and check points, and their wall time
  std::size_t fine_cells = 0;
  std::size_t fine_accepted = 0;
  std::size_t fine_quick_accepted = 0;  // of which on their first 10 checks alone
  std::size_t fine_pathlines = 0;
  double fine_seconds = 0.0;
  std::size_t pixel_pathlines = 0;   // the pixels of failed cells not split that were not nodes already
  double pixel_seconds = 0.0;        // their wall time
  std::size_t sample_pathlines = 0;  // the independent sample
  double sample_seconds = 0.0;
};

struct CertifiedGridOptions {
  double tolerance_px = 0.05;  // bound on |interpolated − exact| per output pixel
  int initial_cell_px = 64;    // coarsest lattice spacing (a power of two)
  std::size_t samples = 1024;  // random pixels checked against their own pathline
  std::uint32_t seed = 1;
  LatticeProfile* profile = nullptr;  // filled when set
};

// f⁻¹ at every output pixel centre (x + 0.5, y + 0.5), row-major, within options.tolerance_px of the exact
// map (certificate.max_error_px_bound); the lattice's nodes are integrated at min(problem tolerance, 0.15 × tolerance),
// or tolerance / 5 where 0.15 × tolerance < 1e-3 px. A cell whose centre, edge midpoints and edges show it well
// within the tolerance is accepted on those, its quarter points not integrated. A failed cell is split when that
// is expected to cost less than its pixels' own pathlines, which it keeps otherwise (always at 2 px), integrated like
// the exact path's at min(problem tolerance, tolerance); a failed 8 px cell is first tried with the quartic through
// plain nodes on its 2 px grid, checked where that interpolant's error peaks. When the lattice would cost more than a
// pathline per pixel, every pixel gets its own pathline instead (the certificate then says exact).
std::vector<Point> certified_inverse_map_grid(WarpBackend& backend, const WarpProblem& problem, int width, int height,
                                              const CertifiedGridOptions& options, const RunControl& control,
                                              WarpCertificate& certificate);

// The certificate of an exact (per-pixel) grid: sample errors are zero by construction, the Jacobian is
// measured on the sample.
WarpCertificate exact_grid_certificate(WarpBackend& backend, const WarpProblem& problem, int width, int height,
                                       const CertifiedGridOptions& options, const RunControl& control);

}  // namespace texwarp
