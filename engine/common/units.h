#pragma once
/// The engine's unit conversions, defined once (JSBSim's `radtodeg`, `fttom` in `FGJSBBase` are the
/// model). Each factor is the exact definition of the unit, so a conversion rounds once: multiply by
/// the factor to go from the unit named after "Per" to the one before it.

#include <numbers>

namespace gesweep {

/// Radians in one degree: π/180.
inline constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;
/// Degrees in one radian: 180/π.
inline constexpr double kDegreesPerRadian = 180.0 / std::numbers::pi;
/// Metres in one international foot: 0.3048 exactly (1959 agreement).
inline constexpr double kMetresPerFoot = 0.3048;
/// Metres per second in one knot: one international nautical mile (1852 m exactly) per hour.
inline constexpr double kMetresPerSecondPerKnot = 1852.0 / 3600.0;

/// An angle in degrees as radians.
constexpr double DegreesToRadians(double angle_deg) { return angle_deg * kRadiansPerDegree; }
/// An angle (or an angular rate) in radians as degrees.
constexpr double RadiansToDegrees(double angle_rad) { return angle_rad * kDegreesPerRadian; }
/// A length in feet as metres.
constexpr double FeetToMetres(double length_ft) { return length_ft * kMetresPerFoot; }
/// A length in metres as feet.
constexpr double MetresToFeet(double length_m) { return length_m / kMetresPerFoot; }
/// A speed in knots as metres per second.
constexpr double KnotsToMetresPerSecond(double speed_kt) { return speed_kt * kMetresPerSecondPerKnot; }
/// A speed in metres per second as knots.
constexpr double MetresPerSecondToKnots(double speed_mps) { return speed_mps / kMetresPerSecondPerKnot; }

}  // namespace gesweep
