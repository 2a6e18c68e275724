// The dispatch of the landing's lane kernels: generic code, which names each architecture's
// instantiation (made in landing_lanes_<isa>.cc) without instantiating it.
#include "engine/control/landing_lanes.h"

#include <xsimd/xsimd.hpp>

#include "engine/common/errors.h"
#include "engine/disturbance/disturbance_field.h"

namespace gesweep::lanes {

template <int W>
LandingLaneKernels<W> LandingLaneKernelsFor(LanesIsa isa) {
  GESWEEP_DEMAND(LanesIsaSupported(isa));
  switch (isa) {
    case LanesIsa::kSse2:
      return {&LandingRk4Stages<xsimd::sse2, W>, &LandingDerivatives<xsimd::sse2, W>};
    case LanesIsa::kAvx2:
      return {&LandingRk4Stages<xsimd::avx2, W>, &LandingDerivatives<xsimd::avx2, W>};
    case LanesIsa::kAvx512:
      return {&LandingRk4Stages<xsimd::avx512f, W>, &LandingDerivatives<xsimd::avx512f, W>};
  }
  GESWEEP_UNREACHABLE();
}

template LandingLaneKernels<1> LandingLaneKernelsFor<1>(LanesIsa);
template LandingLaneKernels<2> LandingLaneKernelsFor<2>(LanesIsa);
template LandingLaneKernels<4> LandingLaneKernelsFor<4>(LanesIsa);
template LandingLaneKernels<8> LandingLaneKernelsFor<8>(LanesIsa);

void LaneHeightTerms(const DisturbanceField* field, double height_m, double& mean_wind_mps,
                     double& sigma_u_mps, double& length_u_m, double& length_w_m) {
  field->HeightTerms(height_m, mean_wind_mps, sigma_u_mps, length_u_m, length_w_m);
}

}  // namespace gesweep::lanes
