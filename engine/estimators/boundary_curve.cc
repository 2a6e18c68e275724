#include "engine/estimators/boundary_curve.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/common/errors.h"
#include "engine/estimators/local_sensitivity.h"
#include "engine/estimators/model_parameter.h"
#include "engine/modal/hurwitz.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Newton in H converges quadratically from a predictor within millimetres; this many steps at most.
constexpr int kNewtonIterations = 12;
// H* from the certified finder and from continuation are the same root to rounding; a difference
// beyond this is another crossing.
constexpr double kSameBranch_m = 1e-6;

ModelParameter Speed() {
  ModelParameter p;
  p.kind = ModelParameterKind::kSpeed;
  return p;
}

struct Root {
  bool hopf = true;
  bool deflated = false;
};

Root RootOf(const BoundaryResult& result) {
  for (const auto& c : result.crossings) {
    if (result.height_m && c.height_m == *result.height_m) return {c.kind != CrossingKind::kReal, c.deflated};
  }
  return {};
}

double Criterion(const Matrix5d& A, const Root& root) {
  const CharacteristicCoefficients a = CharacteristicPolynomial(A);
  if (root.hopf) return root.deflated ? HurwitzDelta3(a) : HurwitzDelta4(a);
  return root.deflated ? a[4] : a[5];
}

// Newton on c(H, u) = 0 from H0; nullopt when it does not converge.
std::optional<double> Correct(const LongitudinalModel& model, double u, double h0, const Root& root) {
  double h = h0;
  for (int i = 0; i < kNewtonIterations; ++i) {
    const Matrix5d A = model.StateMatrix(h, u);
    const HeightDerivative dA = StateMatrixHeightDerivative(model, h, u);
    const double slope = CriterionDirectionalDerivative(A, dA.dA_dH, root.hopf, root.deflated);
    if (!(std::abs(slope) > 0) || !std::isfinite(slope)) return std::nullopt;
    const double step = Criterion(A, root) / slope;
    h -= step;
    if (!std::isfinite(h)) return std::nullopt;
    if (std::abs(step) <= 1e-13 * std::max(1.0, std::abs(h))) return h;
  }
  return std::nullopt;
}

double SpeedDerivative(const LongitudinalModel& model, double u, double h, const Root& root) {
  return ImplicitBoundaryDerivative(model.StateMatrix(h, u), StateMatrixDerivative(model, h, u, Speed()),
                                    StateMatrixHeightDerivative(model, h, u).dA_dH, root.hopf, root.deflated);
}

class Tracer {
 public:
  Tracer(const LongitudinalModel& model, const BoundaryCurveOptions& options)
      : model_(model), options_(options) {}

  BoundaryCurve Run(double lower, double upper) {
    curve_.lower_speed_mps = lower;
    curve_.upper_speed_mps = upper;
    double u = lower;
    BoundaryResult at = Find(u);
    if (at.height_m) StartBranch(u, at);
    double du = std::min(options_.initial_step_mps, upper - lower);
    while (u < upper) {
      const double un = std::min(u + du, upper);
      if (!on_branch_) {
        BoundaryResult next = Find(un);
        if (next.height_m) {
          const double event = Bisect(u, un, [&](double s) { return Find(s).height_m.has_value(); });
          BoundaryResult after = Find(event);
          curve_.events.push_back({event, "appears", kNaN, after.height_m.value_or(kNaN), at.reason});
          StartBranch(event, after);
          u = event;
          du = options_.initial_step_mps;
          continue;
        }
        u = un;
        at = next;
        du = std::min(2 * du, options_.max_step_mps);
        continue;
      }
      const double predicted = h_ + slope_ * (un - u);
      const std::optional<double> corrected = Correct(model_, un, predicted, root_);
      const BoundaryResult check = Find(un);
      const bool same =
          corrected && check.height_m && std::abs(*check.height_m - *corrected) <= kSameBranch_m;
      if (same) {
        const double error = std::abs(*corrected - predicted);
        if (error > 4 * options_.predictor_tolerance_m && du > options_.min_step_mps) {
          ++curve_.rejected_steps;
          du = std::max(0.5 * du, options_.min_step_mps);
          continue;
        }
        Accept(un, *check.height_m, check);
        u = un;
        const double factor = error > 0 ? 0.9 * std::sqrt(options_.predictor_tolerance_m / error) : 2.0;
        du = std::clamp(du * std::clamp(factor, 0.25, 2.0), options_.min_step_mps, options_.max_step_mps);
        continue;
      }
      if (du > options_.min_step_mps) {
        ++curve_.rejected_steps;
        du = std::max(0.5 * du, options_.min_step_mps);
        continue;
      }
      // The branch changes between u and un: locate where.
      const double base_u = u, base_h = h_, base_slope = slope_;
      const Root base_root = root_;
      const double event = Bisect(u, un, [&](double s) {
        const auto h = Correct(model_, s, base_h + base_slope * (s - base_u), base_root);
        const BoundaryResult r = Find(s);
        return h && r.height_m && std::abs(*r.height_m - *h) <= kSameBranch_m;
      });
      const BoundaryResult after = Find(std::min(event + options_.event_tolerance_mps, upper));
      const auto before = Correct(model_, event, base_h + base_slope * (event - base_u), base_root);
      curve_.events.push_back({event, after.height_m ? "jumps" : "ends", before.value_or(kNaN),
                               after.height_m.value_or(kNaN), after.height_m ? "" : after.reason});
      on_branch_ = false;
      u = std::min(event + options_.event_tolerance_mps, upper);
      at = after;
      if (after.height_m) StartBranch(u, after);
      du = options_.initial_step_mps;
    }
    return curve_;
  }

 private:
  BoundaryResult Find(double u) {
    ++curve_.finder_calls;
    return FindBoundary(model_, u, options_.search);
  }

  template <typename Predicate>
  double Bisect(double good, double bad, Predicate holds_at_bad_side) {
    // holds_at_bad_side(bad) differs from holds_at_bad_side(good); returns the first speed past the change.
    const bool at_good = holds_at_bad_side(good);
    while (bad - good > options_.event_tolerance_mps) {
      const double mid = 0.5 * (good + bad);
      (holds_at_bad_side(mid) == at_good ? good : bad) = mid;
    }
    return bad;
  }

  void StartBranch(double u, const BoundaryResult& result) {
    on_branch_ = true;
    ++branch_;
    root_ = RootOf(result);
    Accept(u, *result.height_m, result);
  }

  void Accept(double u, double h, const BoundaryResult& result) {
    h_ = h;
    slope_ = SpeedDerivative(model_, u, h, root_);
    BoundaryCurvePoint point;
    point.speed_mps = u;
    point.height_m = h;
    point.height_over_span = h / model_.aircraft().wingspan_m;
    point.height_speed_derivative = slope_;
    point.certified = result.certified;
    point.branch = branch_;
    for (const auto& c : result.crossings) {
      if (c.height_m == h) {
        point.kind = c.kind;
        point.deflated = c.deflated;
        point.mode = c.mode;
      }
    }
    curve_.points.push_back(point);
    ++curve_.accepted_steps;
  }

  const LongitudinalModel& model_;
  const BoundaryCurveOptions& options_;
  BoundaryCurve curve_;
  bool on_branch_ = false;
  int branch_ = 0;
  Root root_;
  double h_ = 0, slope_ = 0;
};

}  // namespace

BoundaryCurve TraceBoundary(const LongitudinalModel& model, double lower_speed_mps, double upper_speed_mps,
                            const BoundaryCurveOptions& options) {
  GESWEEP_DEMAND(lower_speed_mps > 0 && upper_speed_mps > lower_speed_mps);
  return Tracer(model, options).Run(lower_speed_mps, upper_speed_mps);
}

std::optional<double> BoundaryOnCurve(const LongitudinalModel& model, const BoundaryCurve& curve,
                                      double speed_mps) {
  const auto& p = curve.points;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    if (p[i].branch != p[i + 1].branch || speed_mps < p[i].speed_mps || speed_mps > p[i + 1].speed_mps)
      continue;
    // Cubic Hermite between the two points, then Newton on the criterion.
    const double h = p[i + 1].speed_mps - p[i].speed_mps;
    const double t = h > 0 ? (speed_mps - p[i].speed_mps) / h : 0.0;
    const double h00 = (1 + 2 * t) * (1 - t) * (1 - t), h10 = t * (1 - t) * (1 - t);
    const double h01 = t * t * (3 - 2 * t), h11 = t * t * (t - 1);
    const double guess = h00 * p[i].height_m + h10 * h * p[i].height_speed_derivative +
                         h01 * p[i + 1].height_m + h11 * h * p[i + 1].height_speed_derivative;
    const Root root{p[i].kind != CrossingKind::kReal, p[i].deflated};
    return Correct(model, speed_mps, guess, root);
  }
  if (!p.empty() && speed_mps == p.back().speed_mps) return p.back().height_m;
  return std::nullopt;
}

}  // namespace gesweep
