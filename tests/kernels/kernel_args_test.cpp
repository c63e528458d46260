// The pathline kernel's argument list: indices follow the list, the comparison with a kernel's reported parameters
// finds each kind of difference, and the built kernel reports exactly the host's list.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "kernel_args.hpp"
#include "opencl_device.hpp"
#include "pathline_kernel_args.hpp"
#include "pathline_program.hpp"

namespace texwarp::kernels_detail {
namespace {

using Args = PathlineKernelArgs<float>;

static_assert(Args::index<"n">() == 0);
static_assert(Args::index<"t_start">() == 9);
static_assert(Args::index<"jacobian">() == Args::kCount - 1);

KernelParameters reported() {
  KernelParameters p;
  p.count = Args::kCount;
  for (std::size_t i = 0; i < Args::kCount; ++i) {
    p.names.emplace_back(Args::kNames[i]);
    p.global.push_back(Args::kBuffers[i]);
  }
  return p;
}

TEST(KernelArgs, IndicesArePositionsInTheList) {
  EXPECT_EQ(Args::kCount, 25u);
  EXPECT_EQ(Args::index<"org_x">(), 13u);
  EXPECT_EQ(Args::kNames[Args::index<"event_records">()], "event_records");
  EXPECT_TRUE(Args::kBuffers[Args::index<"scratch">()]);
  EXPECT_FALSE(Args::kBuffers[Args::index<"scratch_stride">()]);
}

TEST(KernelArgs, MismatchNamesTheDifference) {
  EXPECT_EQ(parameter_mismatch(Args::kNames, Args::kBuffers, reported()), "");

  KernelParameters fewer = reported();
  fewer.count -= 1;
  fewer.names.pop_back();
  fewer.global.pop_back();
  EXPECT_EQ(parameter_mismatch(Args::kNames, Args::kBuffers, fewer), "it has 24 parameters, the host binds 25");

  KernelParameters swapped = reported();
  std::swap(swapped.names[9], swapped.names[10]);
  EXPECT_EQ(parameter_mismatch(Args::kNames, Args::kBuffers, swapped),
            "parameter 9 is \"t_end\", the host binds \"t_start\" there");

  KernelParameters value = reported();
  value.global[6] = false;
  EXPECT_EQ(parameter_mismatch(Args::kNames, Args::kBuffers, value),
            "parameter 6 (\"feat\") is a value, the host binds a buffer");

  KernelParameters unnamed{Args::kCount, {}, {}};  // built without -cl-kernel-arg-info: the count alone
  EXPECT_EQ(parameter_mismatch(Args::kNames, Args::kBuffers, unnamed), "");
}

TEST(KernelArgs, TheBuiltKernelTakesExactlyTheHostsList) {
  const DeviceHandle device = select_device({});
  for (const bool jacobian : {false, true}) {
    const cl::Program program = pathline_program(device, {false, jacobian});
    const KernelParameters p = kernel_parameters(cl::Kernel(program, kPathlineKernelName.data()));
    EXPECT_EQ(p.count, Args::kCount);
    ASSERT_EQ(p.names.size(), Args::kCount) << "PoCL reports parameter names with -cl-kernel-arg-info";
    for (std::size_t i = 0; i < Args::kCount; ++i) {
      EXPECT_EQ(p.names[i], Args::kNames[i]) << i;
      EXPECT_EQ(p.global[i], Args::kBuffers[i]) << i;
    }
  }
}

}  // namespace
}  // namespace texwarp::kernels_detail
