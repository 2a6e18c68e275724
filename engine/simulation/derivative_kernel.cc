#include "engine/simulation/derivative_kernel.h"

#include <limits>

#include "engine/common/errors.h"

namespace gesweep {

DensityPolynomial::DensityPolynomial(double field_elevation_m)
    : field_elevation_m_(field_elevation_m),
      center_m_(0.5 * (kPolynomialLow_m + kPolynomialHigh_m)),
      half_width_m_(0.5 * (kPolynomialHigh_m - kPolynomialLow_m)) {
  // ρ(z) = ρ0·τ(z)^n with τ = 1 − L z/T0 and n = g/(R L) − 1. About z_c: τ(z) = τ_c (1 − δ y) with
  // y = z − z_c and δ = L/(T0 τ_c), so ρ = ρ_c Σ_k binom(n, k) (−δ y)^k, ρ_c = IsaDensity(z_c).
  const double exponent = kGravity_mps2 / (kAirGasConstant_JpkgK * kTroposphereLapseRate_Kpm) - 1.0;
  const double altitude_center_m = field_elevation_m + center_m_;
  const double tau_center = 1.0 - kTroposphereLapseRate_Kpm * altitude_center_m / kSeaLevelTemperature_K;
  const double delta = kTroposphereLapseRate_Kpm / (kSeaLevelTemperature_K * tau_center);
  double binomial = 1.0;
  double power = 1.0;
  const double rho_center = IsaDensity(altitude_center_m);
  for (int k = 0; k <= kDegree; ++k) {
    coefficients_[k] = rho_center * binomial * power;
    binomial *= (exponent - k) / (k + 1);
    power *= -delta;
  }
  // Outside the troposphere the polynomial must not hide IsaDensity's NaN: shrink the band to it.
  if (!(std::isfinite(rho_center) && std::isfinite(IsaDensity(field_elevation_m + kPolynomialLow_m)) &&
        std::isfinite(IsaDensity(field_elevation_m + kPolynomialHigh_m)))) {
    half_width_m_ = -1.0;  // never inside: always IsaDensity
  }
}

LinearDerivativeTable::LinearDerivativeTable(const LongitudinalModel& model)
    : density_(model.aircraft().field_elevation_m) {
  GESWEEP_DEMAND(model.options().interpolation == Interpolation::kLinear);
  const CoefficientTable& table = model.table();
  const std::vector<double>& heights = table.heights_m();
  const std::size_t n = heights.size();
  GESWEEP_DEMAND(n >= 2);
  const bool h_derivatives = model.options().h_derivatives;
  auto reduced_at = [&](const CoefficientRow& row) {
    DimensionalDerivatives d =
        ComputeDerivatives(row, model.mass_geometry(), /*density_kgpm3=*/1.0, /*speed_mps=*/1.0);
    if (!h_derivatives) d.Xh = d.Zh = d.Mh = 0.0;
    return Reduce(d);
  };
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  std::vector<std::array<double, kReducedCount>> rows;
  for (const auto& row : table.rows()) rows.push_back(reduced_at(row));

  Segment below;
  below.value = rows.front();
  below.reference_m = heights.front();
  below.low_m = -kInfinity;
  below.high_m = heights.front();
  segments_.push_back(below);
  for (std::size_t i = 1; i < n; ++i) {
    Segment segment;
    segment.reference_m = heights[i - 1];
    segment.low_m = heights[i - 1];
    segment.high_m = heights[i];
    for (int j = 0; j < kReducedCount; ++j) {
      segment.value[j] = rows[i - 1][j];
      segment.slope[j] = (rows[i][j] - rows[i - 1][j]) / (heights[i] - heights[i - 1]);
    }
    segments_.push_back(segment);
  }
  Segment above;
  above.value = reduced_at(table.free_flight());
  above.reference_m = heights.back();
  above.low_m = heights.back();
  above.high_m = kInfinity;
  segments_.push_back(above);
}

std::array<double, LinearDerivativeTable::kReducedCount> LinearDerivativeTable::Reduce(
    const DimensionalDerivatives& d) {
  std::array<double, kReducedCount> r{};
  r[kXu] = d.Xu;
  r[kXw] = d.Xw;
  r[kXh] = d.Xh;
  r[kXde] = d.Xde;
  r[kZu] = d.Zu;
  r[kZw] = d.Zw;
  r[kZh] = d.Zh;
  r[kZde] = d.Zde;
  r[kMu] = d.Mu;
  r[kMw] = d.Mw;
  r[kMq] = d.Mq;
  r[kMh] = d.Mh;
  r[kMde] = d.Mde;
  r[kMwDot] = d.Mw_dot;
  return r;
}

int LinearDerivativeTable::SegmentOf(double height_m) const { return Locate(height_m, 0); }

int LinearDerivativeTable::Locate(double height_m, int start) const {
  if (std::isnan(height_m)) return start;  // the caller's NaN propagates through ρ; any segment will do
  int s = start;
  while (s > 0 && height_m <= segments_[s].low_m) --s;
  while (s + 1 < static_cast<int>(segments_.size()) && height_m > segments_[s].high_m) ++s;
  return s;
}

}  // namespace gesweep
