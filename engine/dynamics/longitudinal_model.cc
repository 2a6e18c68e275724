#include "engine/dynamics/longitudinal_model.h"

#include <cmath>

#include "engine/aircraft/atmosphere.h"
#include "engine/common/errors.h"

namespace gesweep {

DimensionalDerivatives ComputeDerivatives(const CoefficientRow& C, const MassGeometry& mg,
                                          double density_kgpm3, double speed_mps) {
  using enum Coefficient;
  const double u = speed_mps;
  const double c = mg.mean_chord_m;
  const double QS = 0.5 * density_kgpm3 * u * u * mg.wing_area_m2;
  const double QS_m = QS / mg.mass_kg;
  const double QSc_Iy = QS * c / mg.pitch_inertia_kgm2;
  DimensionalDerivatives d;
  d.Xu = -(mg.CDu + 2.0 * mg.CDo) * QS_m / u;
  d.Xw = -(C[Index(CDalpha)] - C[Index(CLo)]) * QS_m / u;
  d.Xh = -C[Index(CDh)] * QS_m / c;
  d.Xde = -mg.CDde * QS_m;
  d.Zu = -(mg.CLu + 2.0 * C[Index(CLo)]) * QS_m / u;
  d.Zw = -(C[Index(CLalpha)] + mg.CDo) * QS_m / u;
  d.Zh = -C[Index(CLh)] * QS_m / c;
  d.Zde = -C[Index(CLde)] * QS_m;
  d.Mu = mg.CMu * QSc_Iy / u;
  d.Mw = C[Index(CMalpha)] * QSc_Iy / u;
  d.Mw_dot = C[Index(CMalphadot)] * (c / (2.0 * u)) * QSc_Iy / u;
  d.Mq = C[Index(CMq)] * (c / (2.0 * u)) * QSc_Iy;
  d.Mh = C[Index(CMh)] * QSc_Iy / c;
  d.Mde = C[Index(CMde)] * QSc_Iy;
  return d;
}

Matrix5d AssembleStateMatrix(const DimensionalDerivatives& d, double u0) {
  Matrix5d A;
  // clang-format off
  A << d.Xu,                d.Xw,                0.0,                 -kGravity_mps2, d.Xh,
       d.Zu,                d.Zw,                u0,                  0.0,            d.Zh,
       d.Mu + d.Mw_dot * d.Zu, d.Mw + d.Mw_dot * d.Zw, d.Mq + d.Mw_dot * u0, 0.0,     d.Mh + d.Mw_dot * d.Zh,
       0.0,                 0.0,                 1.0,                 0.0,            0.0,
       0.0,                 -1.0,                0.0,                 u0,             0.0;
  // clang-format on
  return A;
}

Vector5d AssembleInputMatrix(const DimensionalDerivatives& d) {
  Vector5d B;
  B << d.Xde, d.Zde, d.Mde + d.Mw_dot * d.Zde, 0.0, 0.0;
  return B;
}

LongitudinalModel::LongitudinalModel(Aircraft aircraft, const ModelOptions& options)
    : aircraft_(std::move(aircraft)), options_(options), table_(aircraft_, options_) {
  auto require_positive = [&](const std::optional<double>& value, const char* key) {
    if (value && !(*value > 0.0 && std::isfinite(*value))) {
      throw InputError(aircraft_.source_path, key, ShortNumber(*value), "expected a finite number > 0");
    }
  };
  require_positive(options_.mass_kg, "mass_kg");
  require_positive(options_.pitch_inertia_kgm2, "pitch_inertia_kgm2");
  mass_geometry_.mass_kg = options_.mass_kg.value_or(aircraft_.mass_kg);
  mass_geometry_.pitch_inertia_kgm2 = options_.pitch_inertia_kgm2.value_or(aircraft_.pitch_inertia_kgm2);
  mass_geometry_.mean_chord_m = aircraft_.mean_chord_m;
  mass_geometry_.wing_area_m2 = aircraft_.wing_area_m2;
  mass_geometry_.CDo = aircraft_.CDo * options_.CDo_scale;
  mass_geometry_.CDu = aircraft_.CDu;
  mass_geometry_.CLu = aircraft_.CLu;
  mass_geometry_.CMu = aircraft_.CMu;
  mass_geometry_.CDde = aircraft_.CDde;
}

double LongitudinalModel::DensityAt(double height_m) const {
  if (!std::isfinite(height_m)) return IsaDensity(aircraft_.field_elevation_m);
  return IsaDensity(aircraft_.field_elevation_m + height_m);
}

DimensionalDerivatives LongitudinalModel::DerivativesAt(double height_m, double speed_mps) const {
  DimensionalDerivatives d =
      ComputeDerivatives(table_.At(height_m), mass_geometry_, DensityAt(height_m), speed_mps);
  if (!options_.h_derivatives) d.Xh = d.Zh = d.Mh = 0.0;
  return d;
}

Matrix5d LongitudinalModel::StateMatrix(double height_m, double speed_mps) const {
  return AssembleStateMatrix(DerivativesAt(height_m, speed_mps), speed_mps);
}

Vector5d LongitudinalModel::InputMatrix(double height_m, double speed_mps) const {
  return AssembleInputMatrix(DerivativesAt(height_m, speed_mps));
}

Vector5d LongitudinalModel::StateDerivative(double start_height_m, double u0, const Vector5d& x,
                                            double elevator_rad, const AirVelocity& air) const {
  const DimensionalDerivatives d =
      DerivativesAt(start_height_m + x[kDeltaH], u0 + (x[kDeltaU] - air.u_g_mps));
  return AirRelativeDerivative(d, u0, x, elevator_rad, air);
}

}  // namespace gesweep
