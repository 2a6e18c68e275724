#pragma once
/// Local, analytic sensitivities of the eigenvalues of Eq. (1), of the stability margin σ, and of the
/// boundary height H* (docs/sensitivity.md, "Local sensitivities"; docs/model.md §5–§6):
///   ∂λ/∂p = yᴴ (∂A/∂p) x / (yᴴ x),   ∂σ/∂p = Re ∂λ_σ/∂p,   ∂H*/∂p = −(∂σ/∂p) / (∂σ/∂H) at H*,
/// where λ_σ is the eigenvalue that sets σ (the implicit-function theorem on σ(H*(p), p) = 0).

#include <array>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "engine/dynamics/longitudinal_model.h"
#include "engine/estimators/model_parameter.h"
#include "engine/modal/boundary.h"
#include "engine/modal/modal_analysis.h"

namespace gesweep {

/// Sensitivities with respect to one parameter.
struct ParameterEigenSensitivity {
  ModelParameter parameter;
  double value = 0;  ///< the parameter's current value, in parameter.Unit()
  /// ∂λ_i/∂p, 1/s per unit of p, in the order of ModalAnalysis::eigenvalues (short period ×2,
  /// phugoid ×2, height).
  std::array<std::complex<double>, 5> eigenvalue_derivatives{};
  /// ∂σ/∂p = Re ∂λ_σ/∂p, 1/s per unit of p (NaN when no eigenvalue sets σ).
  double margin_derivative = 0;
  /// false when A at p ± δ is bitwise the same: the parameter does not enter Eq. (1) (CMo, CLα̇, CLq,
  /// CLδe, CMδe, h0/c, and CDh with cdh = zero; with a CG shift CLq does, through CMq), or its effect
  /// is below the rounding of A (CLα̇ ≈ 1e-14 carried into CMα̇ by a CG shift). Its derivatives are 0.
  bool enters_state_matrix = true;
  DerivativeMethod method = DerivativeMethod::kExact;  ///< how ∂A/∂p was obtained
};

/// Eigenvalue and margin sensitivities at one flight condition.
struct EigenSensitivities {
  double height_m = 0;
  double speed_mps = 0;
  ModalAnalysis modal;  ///< AnalyzeModes(A) at (H, u): the eigenvalues and their order
  /// Index into modal.eigenvalues of the eigenvalue that sets σ (for a pair, the member with Im > 0);
  /// −1 when A is not finite or every eigenvalue is neutral.
  int margin_index = -1;
  /// σ minus the largest real part of any other mode: where it is ~0 two modes share σ and σ has a
  /// kink; its derivatives are then one-sided.
  double margin_gap_per_s = 0;
  /// Wilkinson condition number of each eigenvalue (same order); large means nearly defective.
  std::array<double, 5> condition_numbers{};
  /// ∂λ_i/∂H, 1/(s·m), and ∂σ/∂H (NaN at H = ∞).
  std::array<std::complex<double>, 5> height_derivatives{};
  double margin_height_derivative_per_s_per_m = 0;
  HeightDerivative height_step;                       ///< how ∂A/∂H was taken
  std::vector<ParameterEigenSensitivity> parameters;  ///< in the order asked for
};

/// ∂λ/∂p and ∂σ/∂p for every parameter in `parameters` at height H (> 0, may be +∞) and speed u (> 0),
/// and ∂λ/∂H, ∂σ/∂H when H is finite.
EigenSensitivities ComputeEigenSensitivities(
    const LongitudinalModel& model, double height_m, double speed_mps,
    const std::vector<ModelParameter>& parameters = LocalSensitivityParameters());

/// ∂H*/∂p for one parameter.
struct BoundaryParameterSensitivity {
  ModelParameter parameter;
  double value = 0;                         ///< p, in parameter.Unit()
  double margin_derivative = 0;             ///< ∂σ/∂p at (H*, u0), 1/s per unit of p
  double height_derivative = 0;             ///< ∂H*/∂p, m per unit of p (HeightDerivativeUnit)
  double relative_height_derivative_m = 0;  ///< p·∂H*/∂p, m: the change of H* per unit relative change of p
  /// ∂H*/∂p by the implicit-function theorem on the crossing criterion c(H*, p) = 0 of the boundary
  /// (Δ₄ for a Hopf crossing, a₅ for a real one; Δ₃, a₄ where a₅ ≡ 0): −(∂c/∂p)/(∂c/∂H), without
  /// eigenvectors (ImplicitBoundaryDerivative). NaN when the boundary's crossing is not classified.
  double implicit_height_derivative = std::numeric_limits<double>::quiet_NaN();
  bool enters_state_matrix = true;
  DerivativeMethod method = DerivativeMethod::kExact;
};

/// The unit of ∂H*/∂p: "m" for scale factors, "m/kg", "m/(kg m^2)", "m/(m/s)".
std::string HeightDerivativeUnit(const ModelParameter& p);

/// Sensitivities of the boundary H*(u0) of one BoundaryResult.
struct BoundarySensitivities {
  bool valid = false;
  std::string reason;  ///< why not valid: no boundary, σ stationary in H at H*, non-finite A
  double height_m = 0;
  double speed_mps = 0;
  /// The mode whose eigenvalue sets σ at H*: "short_period", "phugoid" or "height".
  std::string mode;
  double margin_height_derivative_per_s_per_m =
      0;                     ///< ∂σ/∂H at H*, 1/(s·m); < 0 at a boundary (stable above)
  EigenSensitivities eigen;  ///< everything at (H*, u0)
  std::vector<BoundaryParameterSensitivity> parameters;  ///< in the order asked for
};

/// The directional derivative of a crossing criterion along dA (Δ₄ or a₅ of det(sI − A); with
/// `deflated`, Δ₃ or a₄ of the quartic factor): exact, by a complex step through Faddeev–LeVerrier
/// (the criteria are polynomials in the entries of A).
double CriterionDirectionalDerivative(const Matrix5d& A, const Matrix5d& dA, bool hopf, bool deflated);

/// ∂H*/∂p = −(∂c/∂p)/(∂c/∂H) for the criterion c of a crossing at (H, u): dA_dp = ∂A/∂p, dA_dH = ∂A/∂H.
double ImplicitBoundaryDerivative(const Matrix5d& A, const Matrix5d& dA_dp, const Matrix5d& dA_dH, bool hopf,
                                  bool deflated);

/// ∂H*/∂p = −(∂σ/∂p)/(∂σ/∂H) at the boundary of `boundary` (found by FindBoundary on `model`).
/// Not valid (with a reason) when the boundary has no H* or ∂σ/∂H is zero or not finite.
BoundarySensitivities ComputeBoundarySensitivities(
    const LongitudinalModel& model, const BoundaryResult& boundary,
    const std::vector<ModelParameter>& parameters = LocalSensitivityParameters());

/// The parameters that enter A, ranked by |p·∂H*/∂p| (largest first): the relative form is the one
/// comparable across parameters of different units.
std::vector<BoundaryParameterSensitivity> RankByRelativeEffect(const BoundarySensitivities& sensitivities);

}  // namespace gesweep
