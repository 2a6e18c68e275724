#pragma once
/// Designs for global sensitivity analysis (docs/sensitivity.md, "Designs"): the Saltelli design in
/// SALib's row layout, from a Boost.Random Sobol sequence, and Morris trajectories. Both return one
/// row per run and one column per parameter, in the parameters' own units.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/analysis/sensitivity_common.h"

namespace gesweep {

/// The row layout of a Saltelli design with SALib's order. For each base sample j = 0..N−1 one block
/// of consecutive rows: A_j, AB_j^(1..D), [BA_j^(1..D) when second order], B_j, where AB^(i) is A with
/// column i taken from B and BA^(i) is B with column i taken from A. N·(2D+2) rows with second order,
/// N·(D+2) without. Indices i count parameters from 0.
struct SaltelliLayout {
  int parameter_count = 0;  ///< D ≥ 1
  int base_samples = 0;     ///< N ≥ 1
  bool second_order = false;

  /// Rows per block: 2D+2 with second order, D+2 without.
  int BlockSize() const { return second_order ? 2 * parameter_count + 2 : parameter_count + 2; }
  /// Rows of the whole design, N·BlockSize().
  std::size_t RowCount() const {
    return static_cast<std::size_t>(base_samples) * static_cast<std::size_t>(BlockSize());
  }
  /// Row of A_j.
  std::size_t RowA(int j) const { return static_cast<std::size_t>(j) * static_cast<std::size_t>(BlockSize()); }
  /// Row of AB_j^(i): A_j with parameter i from B_j.
  std::size_t RowAB(int j, int i) const { return RowA(j) + 1 + static_cast<std::size_t>(i); }
  /// Row of BA_j^(i): B_j with parameter i from A_j. Precondition: second_order.
  std::size_t RowBA(int j, int i) const {
    return RowA(j) + 1 + static_cast<std::size_t>(parameter_count) + static_cast<std::size_t>(i);
  }
  /// Row of B_j.
  std::size_t RowB(int j) const { return RowA(j) + static_cast<std::size_t>(BlockSize()) - 1; }
  /// The block (base sample) a row belongs to.
  int BlockOfRow(std::size_t row) const { return static_cast<int>(row / static_cast<std::size_t>(BlockSize())); }
};

/// The largest number of parameters a Saltelli design can have: the Sobol sequence has dimension 2D
/// and Boost.Random's direction-number table stops at 3667 dimensions.
int MaxSaltelliParameters();

/// Throws InputError naming `source` unless there is at least one range, every bound is finite,
/// lower < upper (and 0 < lower when log-uniform), and the names are non-empty and distinct.
void ValidateRanges(const std::vector<ParameterRange>& ranges, const std::string& source);

/// The Saltelli design (layout above) for uniform parameters on `ranges`. The base matrix [A | B] is
/// the unscrambled Sobol sequence of dimension 2D of Boost.Random (boost::random::sobol, which starts
/// after the all-zero point), with `skip_points` further points skipped: A takes coordinates 1..D,
/// B coordinates D+1..2D, each mapped by ParameterRange::FromUnit. N a power of two keeps
/// the balance properties of the sequence. Throws InputError (source `source`) for bad ranges, N < 1
/// or D > MaxSaltelliParameters().
Eigen::MatrixXd SaltelliDesign(const std::vector<ParameterRange>& ranges, int base_samples, bool second_order,
                               std::uint64_t skip_points = 0, const std::string& source = "design");

/// Step of a Morris design on the unit interval, Δ = p/(2(p−1)) for p levels (Morris 1991).
double MorrisUnitStep(int levels);

/// Morris design: `trajectories` blocks of D+1 consecutive rows. Each trajectory starts at a random
/// point of the p-level grid {0, 1/(p−1), …, 1} (per parameter, a level from which the step stays in
/// [0, 1]) and moves one parameter per row by ±Δ (random sign) in a random order, so every parameter
/// moves exactly once. Unit coordinates are mapped by ParameterRange::FromUnit. Draws come from a
/// Boost.Random mt19937_64 seeded with `seed`. Throws InputError (source `source`) for bad ranges,
/// trajectories < 1, or levels not even and ≥ 2.
Eigen::MatrixXd MorrisDesign(const std::vector<ParameterRange>& ranges, int trajectories, int levels,
                             unsigned long long seed, const std::string& source = "design");

}  // namespace gesweep
