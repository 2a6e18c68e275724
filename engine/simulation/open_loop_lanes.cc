// The dispatch of the open loop's lane kernels: generic code, which names each architecture's
// instantiation (made in open_loop_lanes_<isa>.cc) without instantiating it.
#include "engine/simulation/open_loop_lanes.h"

#include <xsimd/xsimd.hpp>

#include "engine/common/errors.h"

namespace gesweep::lanes {

template <int W>
LaneKernels<W> LaneKernelsFor(LanesIsa isa) {
  GESWEEP_DEMAND(LanesIsaSupported(isa));
  switch (isa) {
    case LanesIsa::kSse2:
      return {&Rk4Stages<xsimd::sse2, W>, &Derivatives<xsimd::sse2, W>};
    case LanesIsa::kAvx2:
      return {&Rk4Stages<xsimd::avx2, W>, &Derivatives<xsimd::avx2, W>};
    case LanesIsa::kAvx512:
      return {&Rk4Stages<xsimd::avx512f, W>, &Derivatives<xsimd::avx512f, W>};
  }
  GESWEEP_UNREACHABLE();
}

template LaneKernels<1> LaneKernelsFor<1>(LanesIsa);
template LaneKernels<2> LaneKernelsFor<2>(LanesIsa);
template LaneKernels<4> LaneKernelsFor<4>(LanesIsa);
template LaneKernels<8> LaneKernelsFor<8>(LanesIsa);

}  // namespace gesweep::lanes
