#pragma once
/// The coefficient table of one aircraft under one set of model options, interpolated in height
/// (docs/model.md §2–§3): piecewise linear or PCHIP between finite rows, the first row held below
/// it, the free-flight row above the last finite row. CDh is derived here.

#include <memory>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/dynamics/model_options.h"

namespace gesweep {

class CoefficientTable {
 public:
  /// Builds the table: scale factors, CDh (docs/model.md §3), CG transfer. Throws InputError when the
  /// options cannot apply to this aircraft (PCHIP with fewer than 4 rows).
  CoefficientTable(const Aircraft& aircraft, const ModelOptions& options);
  ~CoefficientTable();
  CoefficientTable(const CoefficientTable&) = delete;
  CoefficientTable& operator=(const CoefficientTable&) = delete;
  CoefficientTable(CoefficientTable&&) noexcept;
  CoefficientTable& operator=(CoefficientTable&&) noexcept;

  /// All coefficients at height H (metres above ground, may be +∞).
  CoefficientRow At(double height_m) const;

  /// Finite row heights and the derived rows (after scaling, CDh and CG transfer).
  const std::vector<double>& heights_m() const { return heights_m_; }
  const std::vector<CoefficientRow>& rows() const { return rows_; }
  const CoefficientRow& free_flight() const { return free_flight_; }
  Interpolation interpolation() const { return interpolation_; }

 private:
  struct Pchip;
  std::vector<double> heights_m_;
  std::vector<CoefficientRow> rows_;
  CoefficientRow free_flight_{};
  Interpolation interpolation_;
  std::unique_ptr<Pchip> pchip_;
};

/// CDh at each finite row by docs/model.md §3: the gradient of k·CLo² on the non-uniform grid h = H/c,
/// second-order central inside, first-order one-sided at the ends (numpy.gradient, edge_order=1).
std::vector<double> PolarCdh(const std::vector<double>& heights_m, const std::vector<double>& k,
                             const std::vector<double>& CLo, double mean_chord_m);

}  // namespace gesweep
