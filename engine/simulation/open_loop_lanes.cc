// The dispatch of the open loop's lane kernels: generic code, which names each architecture's
// instantiation (made in open_loop_lanes_<isa>.cc) without instantiating it.
#include "engine/simulation/open_loop_lanes.h"

#include "engine/simulation/lanes.h"

namespace gesweep::lanes {

template <int W>
LaneKernels<W> LaneKernelsFor(LanesIsa isa) {
  return PickForIsa(isa, []<class Arch>() {
    return LaneKernels<W>{&Rk4Stages<Arch, W>, &Derivatives<Arch, W>};
  });
}

template LaneKernels<1> LaneKernelsFor<1>(LanesIsa);
template LaneKernels<2> LaneKernelsFor<2>(LanesIsa);
template LaneKernels<4> LaneKernelsFor<4>(LanesIsa);
template LaneKernels<8> LaneKernelsFor<8>(LanesIsa);

}  // namespace gesweep::lanes
