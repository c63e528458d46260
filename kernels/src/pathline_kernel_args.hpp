// The parameter list of the flow_pathlines kernel (kernels/cl/pathline.cl), in its order: the one place that
// names and types the kernel's arguments on the host.
#pragma once

#include <CL/opencl.hpp>

#include <string_view>

#include "kernel_args.hpp"

namespace texwarp::kernels_detail {

inline constexpr std::string_view kPathlineKernelName = "flow_pathlines";

template <class Real>
using PathlineKernelArgs =
    KernelArgs<Arg<"n", cl_int>,                  // positional features
               Arg<"m", cl_int>,                  // gradient features
               Arg<"pairs16", cl_int>,            // n(n−1)/2 rounded up to a multiple of kLanes
               Arg<"pow_mode", cl_int>,           // PowMode
               Arg<"half_alpha", Real>,           // α/2
               Arg<"log_inv_length2", Real>,      // ln(1 / L²)
               Arg<"feat", cl::Buffer>,           // positional records (kPositionalStride reals each)
               Arg<"grad", cl::Buffer>,           // gradient records (kGradientStride reals each)
               Arg<"pairs", cl::Buffer>,          // pair records (kPairArrays arrays of pairs16 reals)
               Arg<"t_start", Real>,              //
               Arg<"t_end", Real>,                //
               Arg<"local_tol", Real>,            // allowed local error per unit time, pixels
               Arg<"first_step", Real>,           // dormand_prince::first_step of the segment
               Arg<"org_x", cl::Buffer>,          // per point (tile): origin
               Arg<"org_y", cl::Buffer>,          //
               Arg<"off_x", cl::Buffer>,          // per point (tile): start offset in, end offset out
               Arg<"off_y", cl::Buffer>,          //
               Arg<"scratch", cl::Buffer>,        // ScratchLayout::stride reals per work-item
               Arg<"scratch_stride", cl_int>,     //
               Arg<"z_offset", cl_int>,           //
               Arg<"acc_offset", cl_int>,         //
               Arg<"events", cl_int>,             // near-collision records
               Arg<"event_records", cl::Buffer>,  // kEventStride reals each
               Arg<"status", cl::Buffer>,         // per work-item (tile): kStatusStride ints
               Arg<"jacobian", cl::Buffer>>;  // per point (tile): kJacobianComponents reals; unused without TW_JACOBIAN

}  // namespace texwarp::kernels_detail
