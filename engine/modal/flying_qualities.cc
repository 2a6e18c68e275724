#include "engine/modal/flying_qualities.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

// The two roots of one mode as a second-order system: its ζ (see ModeRating) and its largest real part.
struct SecondOrder {
  double damping_ratio;
  double max_real_per_s;
};

SecondOrder SecondOrderOf(const ModalAnalysis& modal, int slot, bool split, const ModeProperties& mode) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!split) return {mode.damping_ratio, mode.eigenvalue.real()};
  // A split pair is stored larger real part first (ModalAnalysis::eigenvalues).
  const double l1 = modal.eigenvalues[static_cast<std::size_t>(slot)].real();
  const double l2 = modal.eigenvalues[static_cast<std::size_t>(slot) + 1].real();
  const double product = l1 * l2;
  // s² + 2ζωn s + ωn² = (s − λ1)(s − λ2): ωn² = λ1λ2, 2ζωn = −(λ1 + λ2).
  const double zeta = product > 0 ? -(l1 + l2) / (2.0 * std::sqrt(product)) : nan;
  return {zeta, std::max(l1, l2)};
}

double TimeToDouble_s(double max_real_per_s) {
  return max_real_per_s > 0 ? std::numbers::ln2 / max_real_per_s : std::numeric_limits<double>::infinity();
}

bool ShortPeriodSplit(ModeClassification c) {
  return c == ModeClassification::kShortPeriodSplit || c == ModeClassification::kAllReal;
}
bool PhugoidSplit(ModeClassification c) {
  return c == ModeClassification::kPhugoidSplit || c == ModeClassification::kAllReal;
}

}  // namespace

FlyingQualitiesLevel Worst(FlyingQualitiesLevel a, FlyingQualitiesLevel b) {
  return static_cast<int>(a) >= static_cast<int>(b) ? a : b;
}

ModeRating RateShortPeriod(const ModalAnalysis& modal) {
  const bool split = ShortPeriodSplit(modal.classification);
  const SecondOrder mode = SecondOrderOf(modal, 0, split, modal.short_period);
  ModeRating rating{FlyingQualitiesLevel::kWorseThanLevel3, mode.damping_ratio,
                    TimeToDouble_s(mode.max_real_per_s)};
  // A root that does not decay is no damped second-order system, whatever its ζ (docs/model.md §11).
  if (split && mode.max_real_per_s >= 0) return rating;
  const double zeta = mode.damping_ratio;
  if (zeta >= kShortPeriodLevel1MinDamping && zeta <= kShortPeriodLevel1MaxDamping) {
    rating.level = FlyingQualitiesLevel::kLevel1;
  } else if (zeta >= kShortPeriodLevel2MinDamping && zeta <= kShortPeriodLevel2MaxDamping) {
    rating.level = FlyingQualitiesLevel::kLevel2;
  } else if (zeta >= kShortPeriodLevel3MinDamping) {
    rating.level = FlyingQualitiesLevel::kLevel3;
  }
  return rating;  // ζ < 0.15 or NaN: worse than Level 3
}

ModeRating RatePhugoid(const ModalAnalysis& modal) {
  const bool split = PhugoidSplit(modal.classification);
  const SecondOrder mode = SecondOrderOf(modal, 2, split, modal.phugoid);
  ModeRating rating{FlyingQualitiesLevel::kWorseThanLevel3, mode.damping_ratio,
                    TimeToDouble_s(mode.max_real_per_s)};
  const bool stable_pair = split ? mode.max_real_per_s < 0 : mode.max_real_per_s <= 0;
  if (stable_pair && mode.damping_ratio >= kPhugoidLevel1MinDamping) {
    rating.level = FlyingQualitiesLevel::kLevel1;
  } else if (stable_pair && mode.damping_ratio >= kPhugoidLevel2MinDamping) {
    rating.level = FlyingQualitiesLevel::kLevel2;
  } else if (rating.time_to_double_s >= kPhugoidLevel3MinTimeToDouble_s) {
    rating.level = FlyingQualitiesLevel::kLevel3;
  }
  return rating;
}

FlyingQualities RateFlyingQualities(const ModalAnalysis& modal) {
  GESWEEP_DEMAND(modal.finite);
  FlyingQualities result;
  result.short_period = RateShortPeriod(modal);
  result.phugoid = RatePhugoid(modal);
  result.worst = Worst(result.short_period.level, result.phugoid.level);
  return result;
}

}  // namespace gesweep
