// The per-stage cost model behind --progress's weights (runner/stage_costs.hpp): it grows with the work where the
// stages do, and it reproduces the --timings budgets it was fitted to within a factor of 2.
#include <gtest/gtest.h>

#include "texwarp/runner/stage_costs.hpp"

namespace texwarp::runner {
namespace {

using proto::LatencyStage;

StageWorkload work(double size, std::size_t features, bool exact = false, bool pathlines = true) {
  StageWorkload w;
  w.input_pixels = w.output_pixels = size * size;
  w.features = features;
  w.exact = exact;
  w.pathlines = pathlines;
  return w;
}

TEST(StageCosts, EveryStageCostsSomethingAndGrowsWithItsWork) {
  for (const auto& [stage, name] : proto::EnumNames<LatencyStage>::kTable) {
    EXPECT_GT(predicted_seconds(stage, work(16, 0, false, false)), 0.0) << name;
  }
  for (const LatencyStage s : {LatencyStage::kDecode, LatencyStage::kPathlines, LatencyStage::kSampling,
                               LatencyStage::kEncode, LatencyStage::kWrite}) {
    EXPECT_LT(predicted_seconds(s, work(512, 50)), predicted_seconds(s, work(2048, 50))) << static_cast<int>(s);
  }
  EXPECT_LT(predicted_seconds(LatencyStage::kPathlines, work(1024, 10)),
            predicted_seconds(LatencyStage::kPathlines, work(1024, 200)));
  EXPECT_LT(predicted_seconds(LatencyStage::kPathlines, work(512, 50)),
            predicted_seconds(LatencyStage::kPathlines, work(512, 50, true)));
  EXPECT_LT(predicted_seconds(LatencyStage::kPathlines, work(1024, 50, false, false)),
            predicted_seconds(LatencyStage::kPathlines, work(1024, 50)));
  // check's Jacobian grid (128² points): within a factor of two of what `check --timings` measured on the reference
  // machine (50 independent features 4.3 s, 200 smooth ones 12 s), far above an --exact warp of as many pixels.
  for (const auto& [n, measured] : {std::pair<std::size_t, double>{50, 4.3}, {200, 12.0}}) {
    StageWorkload grid = work(128, n, true);
    grid.jacobian_grid = true;
    const double predicted = predicted_seconds(LatencyStage::kPathlines, grid);
    EXPECT_GT(predicted, measured / 2) << n;
    EXPECT_LT(predicted, measured * 2) << n;
    EXPECT_GT(predicted, 5 * predicted_seconds(LatencyStage::kPathlines, work(128, n, true))) << n;
  }
  EXPECT_LT(predicted_seconds(LatencyStage::kDeviceSetup, work(1024, 0, false, false)),
            predicted_seconds(LatencyStage::kDeviceSetup, work(1024, 50)));
  // A different output size: decode follows the input, the others the output.
  ImageHeader header;
  header.width = 2048;
  header.height = 1024;
  const StageWorkload resized = image_workload(header, 512, 256, 50, false);
  EXPECT_EQ(resized.input_pixels, 2048.0 * 1024.0);
  EXPECT_EQ(resized.output_pixels, 512.0 * 256.0);
  EXPECT_EQ(image_workload(header, 0, 0, 50, true).output_pixels, 2048.0 * 1024.0);
}

// `texwarp warp --timings=json` on the reference machine (2 cores, warm kernel caches; astronaut.png resized,
// bench/whole_command_bench.py's independent and smooth feature sets): seconds measured.
struct Measured {
  double size;
  std::size_t features;
  bool exact;
  bool pathlines;
  LatencyStage stage;
  double seconds;
};

TEST(StageCosts, ReproducesTheMeasuredBudgetsWithinAFactorOfTwo) {
  const Measured rows[] = {
      {512, 10, false, true, LatencyStage::kPathlines, 0.225},
      {512, 50, false, true, LatencyStage::kPathlines, 0.516},
      {1024, 10, false, true, LatencyStage::kPathlines, 0.408},
      {1024, 50, false, true, LatencyStage::kPathlines, 0.623},
      {2048, 10, false, true, LatencyStage::kPathlines, 0.557},
      {2048, 50, false, true, LatencyStage::kPathlines, 1.126},
      {512, 200, false, true, LatencyStage::kPathlines, 3.616},
      {1024, 200, false, true, LatencyStage::kPathlines, 4.697},
      {256, 10, true, true, LatencyStage::kPathlines, 0.242},
      {256, 50, true, true, LatencyStage::kPathlines, 0.488},
      {512, 50, true, true, LatencyStage::kPathlines, 1.400},
      {2048, 0, false, false, LatencyStage::kPathlines, 0.083},
      {512, 0, false, false, LatencyStage::kEncode, 0.077},
      {1024, 0, false, false, LatencyStage::kEncode, 0.271},
      {2048, 0, false, false, LatencyStage::kEncode, 1.016},
      {1024, 50, false, true, LatencyStage::kSampling, 0.129},
      {2048, 50, false, true, LatencyStage::kSampling, 0.738},
      {1024, 0, false, false, LatencyStage::kDecode, 0.053},
      {2048, 50, false, true, LatencyStage::kDecode, 0.235},
      {512, 50, false, true, LatencyStage::kDeviceSetup, 0.168},
  };
  for (const Measured& m : rows) {
    const double predicted = predicted_seconds(m.stage, work(m.size, m.features, m.exact, m.pathlines));
    EXPECT_GT(predicted, m.seconds / 2) << proto::to_string(m.stage) << " " << m.size << "² n=" << m.features;
    EXPECT_LT(predicted, m.seconds * 2) << proto::to_string(m.stage) << " " << m.size << "² n=" << m.features;
  }
}

}  // namespace
}  // namespace texwarp::runner
