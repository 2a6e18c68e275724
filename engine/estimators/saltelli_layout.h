#pragma once
/// The row layout of a Saltelli design (docs/sensitivity.md, "Designs"), stated once: the sweep's
/// `sobol` design makes its rows by it (engine/sweep/design.cc), the archive records it, and the
/// Sobol' estimator (sobol_indices.h) and `gesweep sensitivity` read the rows by it.
///
/// SALib's order: for each base sample j = 0..N−1 one block of consecutive rows
///   A_j, AB_j^(1..D), [BA_j^(1..D) when second order], B_j,
/// where AB^(i) is A with column i taken from B and BA^(i) is B with column i taken from A.
/// N·(2D+2) rows with second order, N·(D+2) without. Indices i count parameters from 0.

#include <cstddef>
#include <cstdint>

namespace gesweep {

/// Rows per Saltelli block of D = `parameter_count` parameters: 2D+2 with second order, D+2 without.
constexpr std::int64_t SaltelliBlockRows(int parameter_count, bool second_order) {
  const std::int64_t D = parameter_count;
  return second_order ? 2 * D + 2 : D + 2;
}

/// Whether column `column` (0..D−1) of row `row_in_block` (0 ≤ row_in_block < SaltelliBlockRows) of a
/// block holds B_j's coordinate (true) or A_j's (false).
constexpr bool SaltelliTakesB(int parameter_count, bool second_order, std::int64_t row_in_block, int column) {
  const std::int64_t D = parameter_count;
  if (row_in_block == 0) return false;                       // A_j
  if (row_in_block <= D) return column == row_in_block - 1;  // AB_j^(i), i = row − 1
  if (second_order && row_in_block <= 2 * D)
    return column != row_in_block - D - 1;  // BA_j^(i), i = row − D − 1
  return true;                              // B_j
}

/// A whole Saltelli design as the estimators hold it in memory (N fits an int there): the row of each
/// kind of point.
struct SaltelliLayout {
  int parameter_count = 0;  ///< D ≥ 1
  int base_samples = 0;     ///< N ≥ 1
  bool second_order = false;

  /// Rows per block: SaltelliBlockRows(D, second order).
  int BlockSize() const { return static_cast<int>(SaltelliBlockRows(parameter_count, second_order)); }
  /// Rows of the whole design, N·BlockSize().
  std::size_t RowCount() const {
    return static_cast<std::size_t>(base_samples) * static_cast<std::size_t>(BlockSize());
  }
  /// Row of A_j.
  std::size_t RowA(int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(BlockSize());
  }
  /// Row of AB_j^(i): A_j with parameter i from B_j.
  std::size_t RowAB(int j, int i) const { return RowA(j) + 1 + static_cast<std::size_t>(i); }
  /// Row of BA_j^(i): B_j with parameter i from A_j. Precondition: second_order.
  std::size_t RowBA(int j, int i) const {
    return RowA(j) + 1 + static_cast<std::size_t>(parameter_count) + static_cast<std::size_t>(i);
  }
  /// Row of B_j.
  std::size_t RowB(int j) const { return RowA(j) + static_cast<std::size_t>(BlockSize()) - 1; }
  /// The block (base sample) a row belongs to.
  int BlockOfRow(std::size_t row) const {
    return static_cast<int>(row / static_cast<std::size_t>(BlockSize()));
  }
};

}  // namespace gesweep
