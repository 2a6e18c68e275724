// The dispatch of the landing's lane kernels: generic code, which names each architecture's
// instantiation (made in landing_lanes_<isa>.cc) without instantiating it.
#include "engine/control/landing_lanes.h"

#include "engine/disturbance/disturbance_field.h"
#include "engine/simulation/lanes.h"

GESWEEP_INSTANTIATE_KERNELS_FOR(gesweep::lanes::LandingKernels);

namespace gesweep::lanes {

void LaneHeightTerms(const DisturbanceField* field, double height_m, double& mean_wind_mps,
                     double& sigma_u_mps, double& length_u_m, double& length_w_m) {
  field->HeightTerms(height_m, mean_wind_mps, sigma_u_mps, length_u_m, length_w_m);
}

}  // namespace gesweep::lanes
