// The open loop's lane kernels (open_loop_lanes.h) for xsimd::sse2, built with the generic x86-64 build's own
// flags (engine/simulation/CMakeLists.txt). Nothing else belongs here: every template this file instantiates
// carries the architecture in its name (lanes.h).
#include "engine/simulation/open_loop_lanes_kernel.h"

GESWEEP_INSTANTIATE_RK_KERNELS(gesweep::lanes::OpenLoopKernels, xsimd::sse2);
