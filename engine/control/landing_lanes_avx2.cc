// The landing's lane kernels (landing_lanes.h) for xsimd::avx2, built with -mavx2, no FMA
// (engine/control/CMakeLists.txt). Nothing else belongs here: every template this file instantiates
// carries the architecture in its name (engine/simulation/lanes.h).
#include "engine/control/landing_lanes_kernel.h"

GESWEEP_INSTANTIATE_RK_KERNELS(gesweep::lanes::LandingKernels, xsimd::avx2);
