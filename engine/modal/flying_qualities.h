#pragma once
/// Flying qualities of the bare airframe: the short-period and phugoid modes of a ModalAnalysis rated
/// against MIL-F-8785C for Category C flight phases (the terminal phases: takeoff, approach, landing);
/// docs/model.md §11. The ground-effect height (subsidence) mode has no requirement and is not rated.

#include <string_view>

#include "engine/common/enum_names.h"
#include "engine/modal/modal_analysis.h"

namespace gesweep {

// MIL-F-8785C limits for Category C, as docs/model.md §11 states them (and §13 says where they were
// checked). Every limit is inclusive: a damping ratio equal to a limit meets it.

/// 3.2.2.1.2, short-period damping, Category A and C: Level 1 is 0.35 ≤ ζ_sp ≤ 1.30.
inline constexpr double kShortPeriodLevel1MinDamping = 0.35;
inline constexpr double kShortPeriodLevel1MaxDamping = 1.30;
/// 3.2.2.1.2, Category A and C: Level 2 is 0.25 ≤ ζ_sp ≤ 2.00.
inline constexpr double kShortPeriodLevel2MinDamping = 0.25;
inline constexpr double kShortPeriodLevel2MaxDamping = 2.00;
/// 3.2.2.1.2: Level 3 is ζ_sp ≥ 0.15, with no upper limit.
inline constexpr double kShortPeriodLevel3MinDamping = 0.15;
/// 3.2.1.2, phugoid stability (every category): Level 1 is ζ_p ≥ 0.04.
inline constexpr double kPhugoidLevel1MinDamping = 0.04;
/// 3.2.1.2: Level 2 is ζ_p ≥ 0.
inline constexpr double kPhugoidLevel2MinDamping = 0.0;
/// 3.2.1.2: Level 3 is a time to double amplitude T2 ≥ 55 s.
inline constexpr double kPhugoidLevel3MinTimeToDouble_s = 55.0;

/// A MIL-F-8785C level of flying qualities; larger is worse.
enum class FlyingQualitiesLevel {
  kLevel1 = 1,           ///< clearly adequate for the mission flight phase
  kLevel2 = 2,           ///< adequate, with some increase in pilot workload or loss of effectiveness
  kLevel3 = 3,           ///< the airplane can be controlled safely
  kWorseThanLevel3 = 4,  ///< meets no level's limit
};
/// "level 1", "level 2", "level 3", "worse than level 3" (ToString: enum_names.h).
GESWEEP_ENUM_NAMES(FlyingQualitiesLevel, {kLevel1, "level 1"}, {kLevel2, "level 2"}, {kLevel3, "level 3"},
                   {kWorseThanLevel3, "worse than level 3"});
/// The worse of two levels.
FlyingQualitiesLevel Worst(FlyingQualitiesLevel a, FlyingQualitiesLevel b);

/// A mode's rating and the quantities it was rated on.
struct ModeRating {
  FlyingQualitiesLevel level = FlyingQualitiesLevel::kWorseThanLevel3;
  /// The damping ratio rated: ζ = −Re λ/|λ| of a complex pair, or of a split pair (two real roots λ1,
  /// λ2 of the same sign) the second-order system's ζ = −(λ1 + λ2)/(2·√(λ1·λ2)), ≥ 1 when both are
  /// stable, ≤ −1 when both are unstable. NaN when the two real roots have opposite signs or one is 0.
  double damping_ratio = 0;
  /// ln 2/max Re λ of the mode's roots when that is > 0 (the time to double amplitude), +∞ otherwise.
  double time_to_double_s = 0;
};

/// The short period rated by 3.2.2.1.2 (Category C). A pair (complex or split, both roots stable) is
/// rated on its ζ; a mode with a root of Re λ ≥ 0 (divergent or, for a split pair, neutral) is worse
/// than Level 3 (docs/model.md §11, a choice).
ModeRating RateShortPeriod(const ModalAnalysis& modal);

/// The phugoid rated by 3.2.1.2: a stable pair (complex or split) on its ζ (a split stable pair has
/// ζ ≥ 1: Level 1); a complex pair with Re λ = 0 is Level 2 (ζ = 0); a mode with a real root ≥ 0 or
/// a complex pair with Re λ > 0 is Level 3 when T2 = ln 2/max Re λ ≥ 55 s (+∞ for a zero root), else
/// worse than Level 3 (docs/model.md §11).
ModeRating RatePhugoid(const ModalAnalysis& modal);

/// Both ratings and the worse of them.
struct FlyingQualities {
  ModeRating short_period, phugoid;
  FlyingQualitiesLevel worst = FlyingQualitiesLevel::kWorseThanLevel3;
};

/// The short period and the phugoid of `modal` rated against MIL-F-8785C Category C. Requires
/// modal.finite (GESWEEP_DEMAND).
FlyingQualities RateFlyingQualities(const ModalAnalysis& modal);

}  // namespace gesweep
