// The landing's lane kernels (landing_lanes.h) for xsimd::avx512f, built with -mavx512f -mavx512dq
// -mavx512vl (engine/control/CMakeLists.txt). Nothing else belongs here: every template this file
// instantiates carries the architecture in its name (engine/simulation/lanes.h).
//
// GCC 12 warns that _mm512_sqrt_pd's _mm512_undefined_pd() (a deliberately uninitialised register,
// "__Y = __Y") is used uninitialised, inside its own header: a false positive (the mask is all ones).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#include "engine/control/landing_lanes_kernel.h"

GESWEEP_INSTANTIATE_RK_KERNELS(gesweep::lanes::LandingKernels, xsimd::avx512f);
#pragma GCC diagnostic pop
