// The per-stage cost table: see stage_costs.hpp.
#include "texwarp/runner/stage_costs.hpp"

#include <algorithm>

namespace texwarp::runner {
namespace {

using proto::LatencyStage;

// Seconds on the reference machine (2 cores, AVX-512), fitted to `texwarp warp --timings=json` budgets with warm
// kernel caches: identity, 10 and 50 independent features on the lattice at 512², 1024², 2048²; 200 smooth ones
// at 512² and 1024²; --exact with 10 and 50 at 256² and 50 at 512²; map-mesh on examples/mesh. Per Mpx: per
// million pixels (the decoded input for decode, the output for the rest). n: features.
constexpr double kStartupS = 0.5;  // library loading (the CLI measures its own)
constexpr double kPlanS = 0.002;   // + kPlanPerPairS·n² (trajectory planning: pairs of features)
constexpr double kPlanPerPairS = 1.5e-7;
constexpr double kDeviceSetupS = 0.15;   // OpenCL context and programs from the driver's cache
constexpr double kDecodePerMpxS = 0.06;  // PNG
constexpr double kClosedFormPerMpxS = 0.02;
// The lattice: a part set by the field (its nodes and cells, growing with n², not with the pixels) and a part per
// output pixel (each cell's interpolation, per-pixel pathlines where cells fail).
constexpr double kLatticeS = 0.15;
constexpr double kLatticePerPairS = 8e-5;
constexpr double kLatticePerMpxS = 0.07;
constexpr double kLatticePerMpxFeatureS = 0.002;
// --exact: every pixel's pathline, the pair loop's n² per step.
constexpr double kExactS = 0.15;
constexpr double kExactPerMpxS = 1.5;
constexpr double kExactPerMpxPairS = 0.002;
// check's Jacobian grid (16 384 points at 512²): 0.16 s with 10 smooth features, 4.3 s with 50 independent ones,
// 12 s with 200 smooth ones; linear in n fits the dense rows (the weights only need the right order).
constexpr double kJacobianGridS = 0.05;
constexpr double kJacobianGridPerMpxFeatureS = 3.6;
constexpr double kSamplingPerMpxS = 0.12;
constexpr double kVerifyS = 0.001;  // + kVerifyPerPairS·n² (the features' own pathlines)
constexpr double kVerifyPerPairS = 3e-7;
constexpr double kEncodePerMpxS = 0.25;  // PNG at the default level 1
constexpr double kWriteS = 0.005;
constexpr double kWritePerMpxS = 0.004;
constexpr double kMappingS = 0.12;  // LSCM and feature placement of examples/mesh/spot.obj's head region

// The smallest weight a stage gets: every stage moves the progress a little.
constexpr double kFloorS = 1e-3;

}  // namespace

StageWorkload image_workload(const ImageHeader& input, int width, int height, std::size_t features, bool exact) {
  StageWorkload work;
  work.input_pixels = static_cast<double>(input.width) * static_cast<double>(input.height);
  work.output_pixels =
      static_cast<double>(width > 0 ? width : input.width) * static_cast<double>(height > 0 ? height : input.height);
  work.features = features;
  work.exact = exact;
  return work;
}

double predicted_seconds(LatencyStage stage, const StageWorkload& work) {
  const double in_mpx = work.input_pixels * 1e-6;
  const double out_mpx = work.output_pixels * 1e-6;
  const auto n = static_cast<double>(work.features);
  const auto maps = static_cast<double>(work.maps);
  double s = 0.0;
  switch (stage) {
    case LatencyStage::kStartup:
      s = kStartupS;
      break;
    case LatencyStage::kPlan:
      s = kPlanS + kPlanPerPairS * n * n;
      break;
    case LatencyStage::kDeviceSetup:
      s = work.pathlines ? kDeviceSetupS : 0.0;
      break;
    case LatencyStage::kDecode:
      s = maps * kDecodePerMpxS * in_mpx;
      break;
    case LatencyStage::kMapping:
      s = kMappingS;
      break;
    case LatencyStage::kPathlines:
      if (!work.pathlines) {
        s = kClosedFormPerMpxS * out_mpx;
      } else if (work.jacobian_grid) {
        s = kJacobianGridS + out_mpx * kJacobianGridPerMpxFeatureS * n;
      } else if (work.exact) {
        s = kExactS + out_mpx * (kExactPerMpxS + kExactPerMpxPairS * n * n);
      } else {
        s = kLatticeS + kLatticePerPairS * n * n + out_mpx * (kLatticePerMpxS + kLatticePerMpxFeatureS * n);
      }
      break;
    case LatencyStage::kSampling:
      s = maps * kSamplingPerMpxS * out_mpx;
      break;
    case LatencyStage::kVerify:
      s = kVerifyS + kVerifyPerPairS * n * n;
      break;
    case LatencyStage::kEncode:
      s = maps * kEncodePerMpxS * out_mpx;
      break;
    case LatencyStage::kWrite:
      s = maps * (kWriteS + kWritePerMpxS * out_mpx);
      break;
  }
  return std::max(s, kFloorS);
}

}  // namespace texwarp::runner
