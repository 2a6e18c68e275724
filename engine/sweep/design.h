#pragma once
/// Designs of experiments: the list of runs of a sweep (docs/sweep.md). Every design enumerates its
/// rows lazily and deterministically: Row(i) depends only on the design's specification and i, so
/// any thread or shard computes any run on its own, and a 10⁸-run grid needs no memory per run.
///
///  - grid:   the cartesian product of its axes, the last axis varying fastest (C order);
///  - list:   explicit rows (inline or from CSV);
///  - lhs:    Latin hypercube, seeded (a keyed Feistel permutation per dimension, cycle-walked);
///  - sobol:  Saltelli's scheme on Boost.Random's Sobol' sequence (row layout: see below);
///  - morris: r trajectories of D+1 rows, p levels, seeded (Morris 1991).
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
#include "engine/estimators/saltelli_layout.h"

namespace gesweep {

enum class DesignKind { kSingle, kGrid, kList, kLhs, kSobol, kMorris };
std::string_view ToString(DesignKind kind);

/// How a sampled parameter's unit-interval coordinate maps to its value.
enum class Distribution {
  kUniform,     ///< lower + u·(upper − lower)
  kLogUniform,  ///< exp(log lower + u·(log upper − log lower)); lower > 0
};
std::string_view ToString(Distribution distribution);

/// One column of a design.
struct DesignParameter {
  ParameterId id = 0;
  std::vector<double> values;                          ///< grid: the axis values (a choice as level indices)
  Distribution distribution = Distribution::kUniform;  ///< lhs, sobol, morris
  double lower = 0, upper = 0;                         ///< lhs, sobol, morris
};

/// A validated design specification (parsed from a study's [design] table).
struct DesignSpec {
  DesignKind kind = DesignKind::kSingle;
  std::vector<DesignParameter> parameters;  ///< the swept parameters, in column order
  std::vector<double> list_values;          ///< list: row-major, parameters.size() per row
  std::int64_t list_rows = 0;
  std::string list_csv;           ///< list: the CSV path when the rows came from one
  std::int64_t samples = 0;       ///< lhs: N
  std::uint64_t seed = 0;         ///< lhs, morris
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

/// The stratum (0..n−1) of point i of dimension `dimension` in a seeded Latin hypercube of n points:
/// a keyed bijection of [0, n). Exposed for tests.
std::int64_t LatinStratum(std::uint64_t seed, int dimension, std::int64_t n, std::int64_t i);

}  // namespace gesweep
