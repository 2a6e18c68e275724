#pragma once
/// The mean wind of MIL-F-8785C, section 3.7, and its logarithmic shear with height
/// (docs/model.md §9). Lengths in metres at the interface; only ratios of lengths enter the profile.

#include "engine/common/enum_names.h"
#include "engine/common/units.h"

namespace gesweep {

/// Height at which the mean wind W20 is given: 20 ft.
inline constexpr double kWindReferenceHeight_m = 20.0 * kMetresPerFoot;
/// Roughness length z0 of the profile for Category C (terminal flight phases): 0.15 ft.
inline constexpr double kTerminalRoughnessLength_m = 0.15 * kMetresPerFoot;
/// Top of the specification's low-altitude region (1000 ft): above it the engine holds the 1000 ft
/// values of the profile and of the turbulence scales (docs/model.md §9, a choice).
inline constexpr double kLowAltitudeCeiling_m = 1000.0 * kMetresPerFoot;

/// How the mean wind varies with height.
enum class WindShear {
  kLogarithmic,  ///< W(h) = W20·ln(h/z0)/ln(20 ft/z0), 0 below z0, held above 1000 ft
  kNone,         ///< W(h) = W20 at every height
};
GESWEEP_ENUM_NAMES(WindShear, {kLogarithmic, "logarithmic"}, {kNone, "none"});

/// The mean wind at height h above the ground, m/s, with the sign of W20 (W20 is the u_g of the
/// mean wind at 20 ft: a headwind is negative). Any finite height; NaN propagates.
double MeanWindAt(double wind_20ft_mps, double height_m, WindShear shear);

}  // namespace gesweep
