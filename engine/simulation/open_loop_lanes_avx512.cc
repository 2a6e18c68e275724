// The open loop's lane kernels (open_loop_lanes.h) for xsimd::avx512f, built with -mavx512f -mavx512dq
// -mavx512vl, no FMA (engine/simulation/CMakeLists.txt). Nothing else belongs here: every template this file
// instantiates carries the architecture in its name (lanes.h).
#include "engine/simulation/open_loop_lanes_kernel.h"

GESWEEP_INSTANTIATE_RK_KERNELS(gesweep::lanes::OpenLoopKernels, xsimd::avx512f);
