// The dispatch of the landing's lane kernels: generic code, which names each architecture's
// instantiation (made in landing_lanes_<isa>.cc) without instantiating it.
#include "engine/control/landing_lanes.h"

#include "engine/disturbance/disturbance_field.h"
#include "engine/simulation/lanes.h"

namespace gesweep::lanes {

template <int W>
LandingLaneKernels<W> LandingLaneKernelsFor(LanesIsa isa) {
  return PickForIsa(isa, []<class Arch>() {
    return LandingLaneKernels<W>{&LandingRk4Stages<Arch, W>, &LandingDerivatives<Arch, W>};
  });
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
