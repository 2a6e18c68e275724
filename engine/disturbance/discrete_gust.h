#pragma once
/// The discrete gust of MIL-F-8785C, section 3.7 ("1 − cosine"), as the full bump the engine flies
/// (docs/model.md §9): v(x) = (v_m/2)(1 − cos(π x/d_m)) for 0 ≤ x ≤ 2 d_m, 0 elsewhere, x the
/// distance flown into the gust relative to the air (m).

namespace gesweep {

/// Gust velocity v(x), m/s, for amplitude v_m (m/s, any sign) and half-length d_m (m, > 0).
double OneMinusCosineGust(double distance_m, double amplitude_mps, double half_length_m);

/// dv/dx, (m/s) per m: (v_m/2)(π/d_m) sin(π x/d_m) inside the bump, 0 outside. Continuous at both
/// ends (the bump is C¹), so the gust needs no breakpoint there.
double OneMinusCosineGustSlope(double distance_m, double amplitude_mps, double half_length_m);

}  // namespace gesweep
