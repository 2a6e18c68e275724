#include "engine/dynamics/coefficient_table.h"

#include <math.h>  // Boost 1.74 pchip.hpp calls an unqualified isnan; this declares ::isnan.

#include <algorithm>
#include <boost/math/interpolators/pchip.hpp>
#include <cmath>

#include "engine/common/errors.h"

namespace gesweep {

struct CoefficientTable::Pchip {
  std::vector<boost::math::interpolators::pchip<std::vector<double>>> columns;
};

std::vector<double> PolarCdh(const std::vector<double>& heights_m, const std::vector<double>& k,
                             const std::vector<double>& CLo, double mean_chord_m) {
  const std::size_t n = heights_m.size();
  GESWEEP_DEMAND(n >= 2 && k.size() == n && CLo.size() == n);
  std::vector<double> h(n), f(n), gradient(n);
  for (std::size_t i = 0; i < n; ++i) {
    h[i] = heights_m[i] / mean_chord_m;
    f[i] = k[i] * CLo[i] * CLo[i];
  }
  gradient[0] = (f[1] - f[0]) / (h[1] - h[0]);
  gradient[n - 1] = (f[n - 1] - f[n - 2]) / (h[n - 1] - h[n - 2]);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    // Second-order accurate on a non-uniform grid (the formula numpy.gradient uses).
    const double left = h[i] - h[i - 1];
    const double right = h[i + 1] - h[i];
    gradient[i] = (left * left * f[i + 1] - right * right * f[i - 1] + (right * right - left * left) * f[i]) /
                  (left * right * (left + right));
  }
  return gradient;
}

namespace {

// The end slope of a PCHIP at a table end, by the three-point shape-preserving formula of MATLAB's
// pchip and SciPy's PchipInterpolator (Moler, Numerical Computing with MATLAB, §3.4): h0, m0 belong to
// the end interval, h1, m1 to its neighbour. Boost's default (the end secant) would differ from both.
double PchipEndSlope(double h0, double h1, double m0, double m1) {
  auto sign = [](double v) { return (v > 0) - (v < 0); };
  const double d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1);
  if (sign(d) != sign(m0)) return 0.0;
  if (sign(m0) != sign(m1) && std::abs(d) > 3.0 * std::abs(m0)) return 3.0 * m0;
  return d;
}

void TransferToCg(CoefficientRow& row, double shift) {
  if (shift == 0.0) return;
  // Moment about a CG `shift` chords aft of the reference: CM' = CM + CL·shift.
  const std::pair<Coefficient, Coefficient> pairs[] = {{Coefficient::CMo, Coefficient::CLo},
                                                       {Coefficient::CMalpha, Coefficient::CLalpha},
                                                       {Coefficient::CMalphadot, Coefficient::CLalphadot},
                                                       {Coefficient::CMq, Coefficient::CLq},
                                                       {Coefficient::CMde, Coefficient::CLde},
                                                       {Coefficient::CMh, Coefficient::CLh}};
  for (const auto& [moment, lift] : pairs) row[Index(moment)] += row[Index(lift)] * shift;
}

}  // namespace

CoefficientTable::CoefficientTable(const Aircraft& aircraft, const ModelOptions& options)
    : heights_m_(aircraft.table_heights_m),
      rows_(aircraft.rows),
      free_flight_(aircraft.free_flight),
      interpolation_(options.interpolation) {
  const auto& scale = options.coefficient_scale;
  auto apply_scale = [&scale](CoefficientRow& row) {
    for (int c = 0; c < kTabulatedCount; ++c) row[c] *= scale[c];
  };
  for (auto& row : rows_) apply_scale(row);
  apply_scale(free_flight_);
  // CDh (docs/model.md §3): derived from the scaled k and CLo, zero in free flight.
  std::vector<double> k, CLo;
  for (const auto& row : rows_) {
    k.push_back(row[Index(Coefficient::k)]);
    CLo.push_back(row[Index(Coefficient::CLo)]);
  }
  std::vector<double> cdh(rows_.size(), 0.0);
  if (options.cdh == CdhMode::kPolar) cdh = PolarCdh(heights_m_, k, CLo, aircraft.mean_chord_m);
  for (std::size_t i = 0; i < rows_.size(); ++i) {
    rows_[i][Index(Coefficient::CDh)] = cdh[i] * scale[Index(Coefficient::CDh)];
  }
  free_flight_[Index(Coefficient::CDh)] = 0.0;

  for (auto& row : rows_) TransferToCg(row, options.cg_shift_over_chord);
  TransferToCg(free_flight_, options.cg_shift_over_chord);

  if (interpolation_ == Interpolation::kPchip) {
    if (heights_m_.size() < 4) {
      throw InputError(aircraft.source_path, "interpolation", "pchip",
                       "PCHIP needs at least 4 finite table rows; this table has " +
                           std::to_string(heights_m_.size()) + " (use linear)");
    }
    pchip_ = std::make_unique<Pchip>();
    for (int c = 0; c < kCoefficientCount; ++c) {
      std::vector<double> x = heights_m_;
      std::vector<double> y;
      for (const auto& row : rows_) y.push_back(row[c]);
      const std::size_t n = x.size();
      auto secant = [&](std::size_t i) { return (y[i + 1] - y[i]) / (x[i + 1] - x[i]); };
      const double left = PchipEndSlope(x[1] - x[0], x[2] - x[1], secant(0), secant(1));
      const double right =
          PchipEndSlope(x[n - 1] - x[n - 2], x[n - 2] - x[n - 3], secant(n - 2), secant(n - 3));
      pchip_->columns.emplace_back(std::move(x), std::move(y), left, right);
    }
  }
}

CoefficientTable::~CoefficientTable() = default;
CoefficientTable::CoefficientTable(CoefficientTable&&) noexcept = default;
CoefficientTable& CoefficientTable::operator=(CoefficientTable&&) noexcept = default;

CoefficientRow CoefficientTable::At(double height_m) const {
  if (height_m <= heights_m_.front()) return rows_.front();
  if (height_m > heights_m_.back()) return free_flight_;
  if (interpolation_ == Interpolation::kPchip) {
    CoefficientRow row;
    for (int c = 0; c < kCoefficientCount; ++c) row[c] = pchip_->columns[c](height_m);
    return row;
  }
  // First row strictly above H; H lies in [heights[i-1], heights[i]].
  const auto upper = std::upper_bound(heights_m_.begin(), heights_m_.end(), height_m);
  const std::size_t i = std::min<std::size_t>(upper - heights_m_.begin(), heights_m_.size() - 1);
  const double t = (height_m - heights_m_[i - 1]) / (heights_m_[i] - heights_m_[i - 1]);
  CoefficientRow row;
  for (int c = 0; c < kCoefficientCount; ++c) {
    row[c] = rows_[i - 1][c] + t * (rows_[i][c] - rows_[i - 1][c]);
  }
  return row;
}

}  // namespace gesweep
