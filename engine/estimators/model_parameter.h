#pragma once
/// The parameters of the longitudinal model that local sensitivities are taken with respect to, and
/// the derivative ∂A/∂p of the state matrix of Eq. (1) (docs/model.md §4–§5; docs/sensitivity.md).
///
/// A tabulated coefficient enters as its scale factor s_c of ModelOptions::coefficient_scale: the
/// whole column (every finite row and the free-flight row) is multiplied by s_c, and derivatives are
/// with respect to s_c at its current value (1 unless a sweep changed it). ∂/∂s_c is therefore the
/// change per unit relative change of the coefficient, in the same unit whatever the coefficient.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/aircraft/coefficient.h"
#include "engine/dynamics/longitudinal_model.h"

namespace gesweep {

/// What a parameter is.
enum class ModelParameterKind {
  kCoefficientScale,  ///< scale factor s_c on a coefficient column (ModelOptions::coefficient_scale)
  kCDoScale,          ///< scale factor on CDo (ModelOptions::CDo_scale)
  kMass,              ///< mass, kg
  kPitchInertia,      ///< pitch moment of inertia Iy, kg·m²
  kSpeed,             ///< reference speed u0, m/s (the argument of StateMatrix)
};

/// One parameter of the model.
struct ModelParameter {
  ModelParameterKind kind = ModelParameterKind::kCoefficientScale;
  Coefficient coefficient = Coefficient::k;  ///< the column, for kCoefficientScale only

  /// "scale.<coefficient>" (as in study files), "scale.CDo", "mass_kg", "pitch_inertia_kgm2", "speed_mps".
  std::string Name() const;
  /// Unit of the parameter's value: "1" for scale factors, "kg", "kg m^2", "m/s".
  std::string_view Unit() const;
};

/// Every parameter, in a fixed order: the 16 coefficient scale factors in Coefficient order (CDh
/// included: its factor scales the derived column), then scale.CDo, mass_kg, pitch_inertia_kgm2,
/// speed_mps.
std::vector<ModelParameter> LocalSensitivityParameters();

/// The parameter of a name given by ModelParameter::Name(); nullopt for an unknown name.
std::optional<ModelParameter> ModelParameterFromName(std::string_view name);

/// The current value of p in `model` at speed `speed_mps` (the scale factor, CDo factor, m, Iy or u0).
double ParameterValue(const LongitudinalModel& model, double speed_mps, const ModelParameter& p);

/// A copy of `model` with p set to `value`. Precondition: p is not kSpeed (speed is an argument of
/// StateMatrix, not part of the model). Throws InputError when the value is not allowed (mass ≤ 0).
LongitudinalModel WithParameter(const LongitudinalModel& model, const ModelParameter& p, double value);

/// How StateMatrixDerivative obtains ∂A/∂p.
enum class DerivativeMethod {
  /// A is a polynomial of degree ≤ 2 in the parameter (in 1/m and 1/Iy for mass and inertia), so the
  /// symmetric difference is the derivative itself, exact to rounding, whatever the step.
  kExact,
  /// A is not polynomial in the parameter: an O(δ²) central difference.
  kCentralDifference,
};

/// Which method applies to p for this model. kExact everywhere except the scale factors of the
/// coefficients that the CG transfer mixes (CL and CM of o, α, α̇, q, δe, h) under PCHIP interpolation
/// with a non-zero cg_shift_over_chord: PCHIP of a sum is not the sum of PCHIPs.
DerivativeMethod StateMatrixDerivativeMethod(const LongitudinalModel& model, const ModelParameter& p);

/// Relative step where A is polynomial in the parameter (DerivativeMethod::kExact): any step gives the
/// derivative; a large one keeps the rounding of A (~1e-16·|A|/step) near 1e-13.
inline constexpr double kExactRelativeStep = 1e-3;
/// Relative step of a true central difference: ≈ ε^(1/3), balancing truncation O(δ²) and rounding ε/δ.
inline constexpr double kCentralDifferenceRelativeStep = 6e-6;

/// ∂A/∂p of Eq. (1) at height H (finite, ≥ 0, or +∞) and speed u, per unit of p (docs/model.md §4–§5).
/// Obtained from A at p ± δ with δ = relative_step·max(|p|, 1) for scale factors and relative_step·p
/// for u0; for m and Iy the difference is taken in 1/m and 1/Iy, in which A is affine, and converted.
/// relative_step ≤ 0 picks kExactRelativeStep or kCentralDifferenceRelativeStep by
/// StateMatrixDerivativeMethod.
Matrix5d StateMatrixDerivative(const LongitudinalModel& model, double height_m, double speed_mps,
                               const ModelParameter& p, double relative_step = 0.0);

/// ∂A/∂H of Eq. (1) at a finite height H, per metre: a central difference (A depends on H through the
/// interpolated table and ρ(H); neither is polynomial in H).
struct HeightDerivative {
  Matrix5d dA_dH = Matrix5d::Zero();
  double step_m = 0;       ///< the step used
  bool one_sided = false;  ///< H sits on a table height (a kink of linear interpolation): the
                           ///< derivative from above (the stable side at a boundary) is given
};

/// Largest height step of StateMatrixHeightDerivative, m: A is nearly affine inside a table segment
/// (ρ varies over kilometres), so truncation is negligible; the step shrinks to stay inside the segment.
inline constexpr double kHeightStep_m = 1e-3;

/// ∂A/∂H at (H, u); steps never straddle a table height. Precondition: H finite.
HeightDerivative StateMatrixHeightDerivative(const LongitudinalModel& model, double height_m,
                                             double speed_mps);

}  // namespace gesweep
