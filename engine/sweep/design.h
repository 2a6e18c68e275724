#pragma once
/// Designs of experiments: the list of runs of a sweep (docs/sweep.md). Every design enumerates its
/// rows lazily and deterministically: Row(i) depends only on the design's specification and i, so
/// any thread or shard computes any run on its own, and a 10⁸-run grid needs no memory per run.
///
///  - grid:   the cartesian product of its axes, the last axis varying fastest (C order);
///  - list:   explicit rows (inline or from CSV);
///  - lhs:    Latin hypercube, seeded (a keyed Feistel permutation per dimension, cycle-walked);
///  - sobol:  Saltelli's scheme on Boost.Random's Sobol' sequence (row layout: see below);
///  - morris: r trajectories of D+1 rows, p levels, seeded (Morris 1991);
///  - monte_carlo: N independent draws, each parameter from its own distribution (normal, truncated
///    normal, uniform, log-uniform, lognormal, or weighted discrete values), seeded.
///
/// These are the only designs of the project: the sensitivity estimators of engine/estimators are fed,
/// and unit-tested, with the rows these classes make. The sobol design's rows follow the Saltelli
/// layout of engine/estimators/saltelli_layout.h; A_j and B_j are the first D and last D coordinates of
/// point j+1 of the 2D-dimensional Sobol' sequence (Boost's engine skips the origin). Every sampled
/// design maps its unit coordinates by ValueAtUnit (engine/estimators/sensitivity_common.h).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/analyses/parameter_catalog.h"
#include "engine/common/enum_names.h"
#include "engine/estimators/saltelli_layout.h"

namespace gesweep {

enum class DesignKind { kSingle, kGrid, kList, kLhs, kSobol, kMorris, kMonteCarlo };
/// The study's `kind` and the archive's design attribute (ToString: enum_names.h).
GESWEEP_ENUM_NAMES(DesignKind, {kSingle, "single"}, {kGrid, "grid"}, {kList, "list"}, {kLhs, "lhs"},
                   {kSobol, "sobol"}, {kMorris, "morris"}, {kMonteCarlo, "monte_carlo"});

/// How a sampled parameter's unit-interval coordinate maps to its value (by the inverse of its
/// cumulative distribution function). lhs, sobol and morris take the first two only.
enum class Distribution {
  kUniform,          ///< lower + u·(upper − lower)
  kLogUniform,       ///< exp(log lower + u·(log upper − log lower)); lower > 0
  kNormal,           ///< mean + sigma·Φ⁻¹(u)
  kTruncatedNormal,  ///< the normal (mean, sigma) conditioned on [truncate_lower, truncate_upper]
  kLogNormal,        ///< exp(mean + sigma·Φ⁻¹(u)): mean and sigma are those of the log of the value
  kDiscrete,         ///< values[k] with probability weights[k] / Σ weights
};
/// The study's and the archive's names of the distributions (ToString: enum_names.h).
GESWEEP_ENUM_NAMES(Distribution, {kUniform, "uniform"}, {kLogUniform, "loguniform"}, {kNormal, "normal"},
                   {kTruncatedNormal, "truncated_normal"}, {kLogNormal, "lognormal"},
                   {kDiscrete, "discrete"});

/// One column of a design.
struct DesignParameter {
  ParameterId id = 0;
  /// grid: the axis values; monte_carlo discrete: the values drawn (a choice as level indices)
  std::vector<double> values;
  Distribution distribution = Distribution::kUniform;  ///< lhs, sobol, morris, monte_carlo
  /// lhs, sobol, morris: the bounds. monte_carlo: the smallest and largest value a draw can take
  /// (MonteCarloValue at the extreme unit coordinates), which the study checks against the parameter.
  double lower = 0, upper = 0;
  double mean = 0, sigma = 0;                     ///< monte_carlo normal kinds (lognormal: of the log)
  double truncate_lower = 0, truncate_upper = 0;  ///< monte_carlo truncated normal
  std::vector<double> weights;                    ///< monte_carlo discrete: one > 0 per value
};

/// A validated design specification (parsed from a study's [design] table).
struct DesignSpec {
  DesignKind kind = DesignKind::kSingle;
  std::vector<DesignParameter> parameters;  ///< the swept parameters, in column order
  std::vector<double> list_values;          ///< list: row-major, parameters.size() per row
  std::int64_t list_rows = 0;
  std::string list_csv;           ///< list: the CSV path when the rows came from one
  std::int64_t samples = 0;       ///< lhs, monte_carlo: N
  std::uint64_t seed = 0;         ///< lhs, morris, monte_carlo
  std::int64_t base_samples = 0;  ///< sobol: N
  bool second_order = false;      ///< sobol
  std::int64_t trajectories = 0;  ///< morris: r
  int levels = 0;                 ///< morris: p (even)
};

/// A design: `run_count()` rows of `columns()` values.
class Design {
 public:
  virtual ~Design() = default;
  /// Number of runs.
  virtual std::int64_t run_count() const = 0;
  /// Writes the values of row `index` (0 ≤ index < run_count()) into `values` (columns() of them).
  /// Thread-safe.
  virtual void Row(std::int64_t index, double* values) const = 0;
  const DesignSpec& spec() const { return spec_; }
  int column_count() const { return static_cast<int>(spec_.parameters.size()); }

 protected:
  explicit Design(DesignSpec spec) : spec_(std::move(spec)) {}
  DesignSpec spec_;
};

/// Builds the design of a validated spec. GESWEEP_DEMAND on an invalid spec (the study parser
/// validates it first).
std::unique_ptr<Design> MakeDesign(DesignSpec spec);

/// Number of runs a spec gives, or −1 when it would exceed 2⁶² (refused by the study parser).
std::int64_t CountRuns(const DesignSpec& spec);

/// The most parameters a sobol design may sample (the study parser refuses more). Boost.Random's
/// Sobol' tables hold 3667 dimensions and the design draws 2D of them; 1000 keeps a margin (checked
/// at compile time in design.cc).
inline constexpr int kMaximumSobolParameters = 1000;

/// The most levels p of a morris design (the study parser refuses more).
inline constexpr int kMaximumMorrisLevels = 1000;

/// The points of the Sobol' sequence used by the sobol design: coordinate d of point j (j ≥ 0
/// gives Boost's point j+1, the origin skipped), for a sequence of `dimension` coordinates.
void SobolPoint(int dimension, std::int64_t j, double* coordinates);

/// Maps a unit-interval coordinate through a design parameter's distribution.
double MapUnit(const DesignParameter& parameter, double u);

/// The monte_carlo design's unit coordinate of parameter `id` in run `index`, in (0, 1): a pure
/// function of (seed, run index, parameter name), counter-based like engine/disturbance/run_noise.h:
///   run key = HashWords(seed ^ "MONTE_CA", index)            (engine/sweep/hashing.h)
///   bits    = HashWords(run key, FNV-1a 64 of the parameter's name)
///   u       = ((bits >> 12) + 0.5)·2⁻⁵², in [2⁻⁵³, 1 − 2⁻⁵³] (52 random bits: every u and 1 − u
///             is exact in a double, so both tails are symmetric and u never rounds to 0 or 1)
/// Keyed by the name rather than the column, a parameter draws the same values when another is
/// added to or removed from the design (common random numbers between studies of one seed).
double MonteCarloUnit(std::uint64_t seed, std::int64_t index, ParameterId id);

/// The smallest and largest unit coordinates MonteCarloUnit gives.
inline constexpr double kMonteCarloUnitLow = 0x1.0p-53;
inline constexpr double kMonteCarloUnitHigh = 1.0 - 0x1.0p-53;

/// Maps a unit coordinate through a monte_carlo parameter's distribution (inverse CDF; a discrete
/// parameter takes the first value whose cumulative weight exceeds u·Σ weights).
double MonteCarloValue(const DesignParameter& parameter, double u);

/// Maps a standard-normal coordinate z through a monte_carlo parameter's distribution: the value
/// whose cumulative probability is Φ(z), as a subset simulation's random parameters join its
/// standard-normal space (engine/risk). Normal and lognormal take z itself (mean + σz and
/// exp(mean + σz)), exact in both tails however far; the other kinds are MonteCarloValue at
/// u = Φ(z) held within [kMonteCarloUnitLow, kMonteCarloUnitHigh], so they reach the extreme values
/// of a monte_carlo design and no further. z is finite.
double MonteCarloValueAtNormal(const DesignParameter& parameter, double z);

/// The probability a truncated normal parameter's interval holds under the untruncated normal
/// (the study parser refuses an interval whose probability underflows).
double TruncatedNormalMass(const DesignParameter& parameter);

/// A one-line statement of a design parameter's distribution, e.g. "normal(mean=32, sigma=0.5)".
std::string DescribeDistribution(const DesignParameter& parameter);

/// The stratum (0..n−1) of point i of dimension `dimension` in a seeded Latin hypercube of n points:
/// a keyed bijection of [0, n). Exposed for tests.
std::int64_t LatinStratum(std::uint64_t seed, int dimension, std::int64_t n, std::int64_t i);

}  // namespace gesweep
