#include "engine/estimators/model_parameter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/common/errors.h"

namespace gesweep {

namespace {

// The name and unit of each kind of parameter; a coefficient scale's name is this prefix and the
// coefficient's name.
struct KindNames {
  ModelParameterKind kind;
  std::string_view name;
  std::string_view unit;
};
constexpr KindNames kKindNames[] = {{ModelParameterKind::kCoefficientScale, "scale.", "1"},
                                    {ModelParameterKind::kCDoScale, "scale.CDo", "1"},
                                    {ModelParameterKind::kMass, "mass_kg", "kg"},
                                    {ModelParameterKind::kPitchInertia, "pitch_inertia_kgm2", "kg m^2"},
                                    {ModelParameterKind::kSpeed, "speed_mps", "m/s"}};

const KindNames& NamesOf(ModelParameterKind kind) {
  for (const KindNames& names : kKindNames) {
    if (names.kind == kind) return names;
  }
  GESWEEP_UNREACHABLE();
}

}  // namespace

std::string ModelParameter::Name() const {
  std::string name(NamesOf(kind).name);
  if (kind == ModelParameterKind::kCoefficientScale) name += kCoefficientNames[Index(coefficient)];
  return name;
}

std::string_view ModelParameter::Unit() const { return NamesOf(kind).unit; }

std::vector<ModelParameter> LocalSensitivityParameters() {
  std::vector<ModelParameter> parameters;
  parameters.reserve(kCoefficientCount + 4);  // the coefficient scales, CDo, mass, inertia, speed
  for (int c = 0; c < kCoefficientCount; ++c) {
    parameters.push_back({ModelParameterKind::kCoefficientScale, static_cast<Coefficient>(c)});
  }
  parameters.push_back({ModelParameterKind::kCDoScale});
  parameters.push_back({ModelParameterKind::kMass});
  parameters.push_back({ModelParameterKind::kPitchInertia});
  parameters.push_back({ModelParameterKind::kSpeed});
  return parameters;
}

std::optional<ModelParameter> ModelParameterFromName(std::string_view name) {
  for (const auto& p : LocalSensitivityParameters()) {
    if (p.Name() == name) return p;
  }
  return std::nullopt;
}

double ParameterValue(const LongitudinalModel& model, double speed_mps, const ModelParameter& p) {
  switch (p.kind) {
    case ModelParameterKind::kCoefficientScale:
      return model.options().coefficient_scale[Index(p.coefficient)];
    case ModelParameterKind::kCDoScale:
      return model.options().CDo_scale;
    case ModelParameterKind::kMass:
      return model.mass_geometry().mass_kg;
    case ModelParameterKind::kPitchInertia:
      return model.mass_geometry().pitch_inertia_kgm2;
    case ModelParameterKind::kSpeed:
      return speed_mps;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

LongitudinalModel WithParameter(const LongitudinalModel& model, const ModelParameter& p, double value) {
  GESWEEP_DEMAND(p.kind != ModelParameterKind::kSpeed);
  ModelOptions options = model.options();
  switch (p.kind) {
    case ModelParameterKind::kCoefficientScale:
      options.coefficient_scale[Index(p.coefficient)] = value;
      break;
    case ModelParameterKind::kCDoScale:
      options.CDo_scale = value;
      break;
    case ModelParameterKind::kMass:
      options.mass_kg = value;
      break;
    case ModelParameterKind::kPitchInertia:
      options.pitch_inertia_kgm2 = value;
      break;
    case ModelParameterKind::kSpeed:
      break;
  }
  return LongitudinalModel(model.aircraft(), options);
}

DerivativeMethod StateMatrixDerivativeMethod(const LongitudinalModel& model, const ModelParameter& p) {
  if (p.kind != ModelParameterKind::kCoefficientScale) return DerivativeMethod::kExact;
  const ModelOptions& options = model.options();
  if (options.interpolation != Interpolation::kPchip || options.cg_shift_over_chord == 0.0) {
    return DerivativeMethod::kExact;
  }
  using enum Coefficient;
  static constexpr Coefficient kTransferred[] = {CMo, CLo, CMalpha, CLalpha, CMalphadot, CLalphadot,
                                                 CMq, CLq, CMde,    CLde,    CMh,        CLh};
  return std::find(std::begin(kTransferred), std::end(kTransferred), p.coefficient) != std::end(kTransferred)
             ? DerivativeMethod::kCentralDifference
             : DerivativeMethod::kExact;
}

Matrix5d StateMatrixDerivative(const LongitudinalModel& model, double height_m, double speed_mps,
                               const ModelParameter& p, double relative_step) {
  if (relative_step <= 0.0) {
    relative_step = StateMatrixDerivativeMethod(model, p) == DerivativeMethod::kExact
                        ? kExactRelativeStep
                        : kCentralDifferenceRelativeStep;
  }
  const double value = ParameterValue(model, speed_mps, p);
  switch (p.kind) {
    case ModelParameterKind::kSpeed: {
      // Q = ½ρu² over powers of u in Table 1 and the kinematic u0 make every entry of A a polynomial
      // of degree ≤ 2 in u (Mẇ ∝ u⁰, Zh ∝ u²): the symmetric difference is exact.
      const double du = relative_step * value;
      return (model.StateMatrix(height_m, speed_mps + du) - model.StateMatrix(height_m, speed_mps - du)) /
             (2.0 * du);
    }
    case ModelParameterKind::kMass:
    case ModelParameterKind::kPitchInertia: {
      // X and Z rows scale with 1/m, M rows with 1/Iy, and Mẇ·Z products with both once: A is affine
      // in w = 1/p. dA/dp = −w²·dA/dw.
      const double w = 1.0 / value;
      const double dw = relative_step * w;
      const Matrix5d plus = WithParameter(model, p, 1.0 / (w + dw)).StateMatrix(height_m, speed_mps);
      const Matrix5d minus = WithParameter(model, p, 1.0 / (w - dw)).StateMatrix(height_m, speed_mps);
      return -(w * w) * (plus - minus) / (2.0 * dw);
    }
    case ModelParameterKind::kCoefficientScale:
    case ModelParameterKind::kCDoScale: {
      // Every column is multiplied by its factor before interpolation, which is linear (or, for PCHIP,
      // homogeneous); A is affine in each factor except s_CLo, which enters CDh = d(k·CLo²)/dh squared.
      const double ds = relative_step * std::max(std::abs(value), 1.0);
      const Matrix5d plus = WithParameter(model, p, value + ds).StateMatrix(height_m, speed_mps);
      const Matrix5d minus = WithParameter(model, p, value - ds).StateMatrix(height_m, speed_mps);
      return (plus - minus) / (2.0 * ds);
    }
  }
  return Matrix5d::Constant(std::numeric_limits<double>::quiet_NaN());
}

HeightDerivative StateMatrixHeightDerivative(const LongitudinalModel& model, double height_m,
                                             double speed_mps) {
  GESWEEP_DEMAND(std::isfinite(height_m));
  // Below this distance to a table height, H is taken to sit on it: a symmetric step would be so small
  // that rounding (~1e-16/step relative) would dominate.
  constexpr double kOnKnot_m = 1e-7;
  const auto& knots = model.table().heights_m();
  double below = std::numeric_limits<double>::infinity(), above = below;  // distances to the knots around H
  bool on_knot = false;
  for (double knot : knots) {
    const double distance = knot - height_m;
    if (std::abs(distance) <= kOnKnot_m) {
      on_knot = true;
    } else if (distance > 0) {
      above = std::min(above, distance);
    } else {
      below = std::min(below, -distance);
    }
  }
  HeightDerivative result;
  auto A = [&](double h) { return model.StateMatrix(h, speed_mps); };
  if (!on_knot) {
    result.step_m = std::min({kHeightStep_m, 0.5 * below, 0.5 * above});
    result.dA_dH = (A(height_m + result.step_m) - A(height_m - result.step_m)) / (2.0 * result.step_m);
    return result;
  }
  // Second-order one-sided difference from above: (−3A(H) + 4A(H+h) − A(H+2h)) / (2h).
  result.one_sided = true;
  result.step_m = std::min(kHeightStep_m, 0.25 * above);
  const double h = result.step_m;
  result.dA_dH =
      (-3.0 * A(height_m + kOnKnot_m) + 4.0 * A(height_m + kOnKnot_m + h) - A(height_m + kOnKnot_m + 2 * h)) /
      (2.0 * h);
  return result;
}

}  // namespace gesweep
