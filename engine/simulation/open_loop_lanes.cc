// The dispatch of the open loop's lane kernels: generic code, which names each architecture's
// instantiation (made in open_loop_lanes_<isa>.cc) without instantiating it.
#include "engine/simulation/open_loop_lanes.h"

#include "engine/simulation/lanes.h"

GESWEEP_INSTANTIATE_KERNELS_FOR(gesweep::lanes::OpenLoopKernels);
