// The landing's lane kernels (landing_lanes.h) for xsimd::sse2, built with the build's flags
// (engine/control/CMakeLists.txt). Nothing else belongs here: every template this file instantiates
// carries the architecture in its name (engine/simulation/lanes.h).
#include "engine/control/landing_lanes_kernel.h"

GESWEEP_INSTANTIATE_RK_KERNELS(gesweep::lanes::LandingKernels, xsimd::sse2);
