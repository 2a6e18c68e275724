#pragma once
/// The International Standard Atmosphere, troposphere (ISO 2533:1975), used for ρ(H) (docs/model.md §1).

namespace gesweep {

inline constexpr double kGravity_mps2 = 9.80665;             ///< standard gravity
inline constexpr double kSeaLevelDensity_kgpm3 = 1.225;      ///< ISA ρ0
inline constexpr double kSeaLevelTemperature_K = 288.15;     ///< ISA T0
inline constexpr double kTroposphereLapseRate_Kpm = 0.0065;  ///< ISA temperature lapse rate
inline constexpr double kAirGasConstant_JpkgK = 287.05287;   ///< specific gas constant of dry air
inline constexpr double kTropopauseAltitude_m = 11000.0;     ///< top of the troposphere

/// ISA density at a geopotential altitude in the troposphere, kg/m³:
/// ρ = ρ0 (T/T0)^(g/(R L) − 1), T = T0 − L·altitude. Altitude in metres, in [−610, 11000];
/// outside that range the troposphere formula is not valid and the result is NaN.
double IsaDensity(double altitude_m);

}  // namespace gesweep
