// The warm-up launch (private): one run of a pathline kernel variant on a tiny problem, through the launcher's real
// launch shape, so that the driver compiles and caches everything a real run of that variant needs.
#pragma once

#include "kernel_prelude.hpp"
#include "opencl_device.hpp"

namespace texwarp::kernels_detail {

// Builds `variant` in device.context and launches it once on a few points of a three-feature problem. Throws
// OpenClError as PathlineLauncher::run, NumericalError should the tiny run fail.
void launch_variant_once(const DeviceHandle& device, KernelVariant variant);

}  // namespace texwarp::kernels_detail
