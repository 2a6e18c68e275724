#pragma once
/// The boundary as a curve H*(u0) (issue 16; docs/model.md, "The boundary by the Hurwitz criterion"):
/// traced by natural-parameter continuation in the speed on the crossing criterion c(H, u0) = 0 of
/// the boundary's crossing (Δ₄ for a Hopf crossing, a₅ for a real one): a tangent predictor from the
/// implicit-function theorem (dH*/du0 = −c_u/c_H), a Newton corrector in H, steps adapted to the
/// curvature (the predictor's error ≈ ½ H*'' Δu², kept near a tolerance). At every accepted point the
/// certified finder confirms the point is still H*; where it is not, the speed at which the branch
/// appears, ends or H* jumps to another crossing is located by bisection.

#include <optional>
#include <string>
#include <vector>

#include "engine/modal/boundary.h"

namespace gesweep {

/// How to trace.
struct BoundaryCurveOptions {
  double initial_step_mps = 0.5;
  double max_step_mps = 2.0;
  double min_step_mps = 1e-3;
  /// The predictor may miss the corrected H* by this much; the step adapts to keep it there, m.
  double predictor_tolerance_m = 2e-3;
  /// Events (a branch appearing, ending, jumping) are located to this width in speed, m/s.
  double event_tolerance_mps = 1e-6;
  BoundaryOptions search;  ///< the certified finder's options at each point
};

/// One point of the traced curve.
struct BoundaryCurvePoint {
  double speed_mps = 0;
  double height_m = 0;
  double height_over_span = 0;
  double height_speed_derivative = 0;  ///< dH*/du0, m/(m/s), by the implicit-function theorem
  CrossingKind kind = CrossingKind::kHopf;
  bool deflated = false;   ///< the criterion is that of the quartic factor (a₅ ≡ 0)
  std::string mode;        ///< the crossing mode
  bool certified = false;  ///< the certified finder's verdict at this speed
  int branch = 0;          ///< index of the branch (a new one after each event)
};

/// Where the curve changes branch.
struct BoundaryCurveEvent {
  double speed_mps = 0;  ///< located to BoundaryCurveOptions::event_tolerance_mps
  /// "appears" (no boundary below this speed, one above), "ends" (the reverse), "jumps" (H* moves
  /// to another crossing).
  std::string what;
  double height_below_m = 0, height_above_m = 0;  ///< H* on each side (NaN where there is none)
  std::string reason;                             ///< the finder's reason on the side without a boundary
};

/// The traced curve over [lower, upper] speeds, ascending.
struct BoundaryCurve {
  std::vector<BoundaryCurvePoint> points;
  std::vector<BoundaryCurveEvent> events;
  int accepted_steps = 0, rejected_steps = 0, finder_calls = 0;
  double lower_speed_mps = 0, upper_speed_mps = 0;
};

/// Traces H*(u0) for u0 from lower to upper (> lower > 0).
BoundaryCurve TraceBoundary(const LongitudinalModel& model, double lower_speed_mps, double upper_speed_mps,
                            const BoundaryCurveOptions& options = {});

/// H* at `speed_mps` on the traced curve: Newton on the criterion from the curve's cubic Hermite
/// interpolant between its neighbouring points of one branch; nullopt where the curve has no branch.
std::optional<double> BoundaryOnCurve(const LongitudinalModel& model, const BoundaryCurve& curve,
                                      double speed_mps);

}  // namespace gesweep
