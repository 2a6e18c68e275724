#include "engine/estimators/local_sensitivity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "engine/common/errors.h"
#include "engine/estimators/eigen_sensitivity.h"
#include "engine/modal/hurwitz.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// For each slot of ModalAnalysis::eigenvalues, the index of the same eigenvalue in `system`
/// (closest pairs first, each used once).
std::array<Eigen::Index, 5> MatchToModal(const ModalAnalysis& modal, const EigenSystem& system) {
  std::vector<std::tuple<double, int, Eigen::Index>> candidates;
  for (int slot = 0; slot < 5; ++slot) {
    for (Eigen::Index i = 0; i < system.eigenvalues.size(); ++i) {
      candidates.emplace_back(std::abs(modal.eigenvalues[slot] - system.eigenvalues[i]), slot, i);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::array<Eigen::Index, 5> match{};
  std::array<bool, 5> slot_taken{};
  std::vector<bool> taken(system.eigenvalues.size(), false);
  for (const auto& [distance, slot, i] : candidates) {
    if (slot_taken[slot] || taken[i]) continue;
    slot_taken[slot] = true;
    taken[i] = true;
    match[slot] = i;
  }
  return match;
}

bool IsNeutral(std::complex<double> z) {
  // AnalyzeModes stores real roots with an exactly zero imaginary part.
  return z.imag() == 0.0 && std::abs(z.real()) <= kNeutralEigenvalueTolerance_per_s;
}

/// The eigenvalue derivatives in modal order; exactly real for real eigenvalues (the imaginary part of
/// the derivative of a simple real eigenvalue of a real matrix is rounding).
std::array<std::complex<double>, 5> InModalOrder(const ModalAnalysis& modal,
                                                 const std::array<Eigen::Index, 5>& match,
                                                 const Eigen::VectorXcd& derivatives) {
  std::array<std::complex<double>, 5> ordered{};
  for (int slot = 0; slot < 5; ++slot) {
    ordered[slot] = derivatives[match[slot]];
    if (modal.eigenvalues[slot].imag() == 0.0) ordered[slot] = {ordered[slot].real(), 0.0};
  }
  return ordered;
}

}  // namespace

EigenSensitivities ComputeEigenSensitivities(const LongitudinalModel& model, double height_m,
                                             double speed_mps,
                                             const std::vector<ModelParameter>& parameters) {
  EigenSensitivities result;
  result.height_m = height_m;
  result.speed_mps = speed_mps;
  const Matrix5d A = model.StateMatrix(height_m, speed_mps);
  result.modal = AnalyzeModes(A);
  const std::complex<double> nan_z{kNaN, kNaN};
  result.condition_numbers.fill(kNaN);
  result.height_derivatives.fill(nan_z);
  result.margin_height_derivative_per_s_per_m = kNaN;
  result.margin_gap_per_s = kNaN;
  if (!result.modal.finite) {
    for (const auto& p : parameters) {
      ParameterEigenSensitivity row;
      row.parameter = p;
      row.value = ParameterValue(model, speed_mps, p);
      row.eigenvalue_derivatives.fill(nan_z);
      row.margin_derivative = kNaN;
      result.parameters.push_back(row);
    }
    return result;
  }

  const EigenSystem system = ComputeEigenSystem(A);
  const auto match = MatchToModal(result.modal, system);
  for (int slot = 0; slot < 5; ++slot) result.condition_numbers[slot] = system.condition_numbers[match[slot]];

  const auto& eigenvalues = result.modal.eigenvalues;
  for (int slot = 0; slot < 5; ++slot) {
    if (IsNeutral(eigenvalues[slot])) continue;
    if (result.margin_index < 0 || eigenvalues[slot].real() > eigenvalues[result.margin_index].real()) {
      result.margin_index = slot;
    }
  }
  if (result.margin_index >= 0) {
    // The conjugate partner shares σ by symmetry; any other non-neutral eigenvalue is another mode.
    const int m = result.margin_index;
    const int partner = (m == 0 || m == 2) && eigenvalues[m].imag() != 0.0 ? m + 1 : -1;
    double next = -std::numeric_limits<double>::infinity();
    for (int slot = 0; slot < 5; ++slot) {
      if (slot == m || slot == partner || IsNeutral(eigenvalues[slot])) continue;
      next = std::max(next, eigenvalues[slot].real());
    }
    result.margin_gap_per_s = eigenvalues[m].real() - next;
  }
  auto margin_of = [&result](const std::array<std::complex<double>, 5>& derivatives) {
    return result.margin_index >= 0 ? derivatives[result.margin_index].real() : kNaN;
  };

  if (std::isfinite(height_m)) {
    result.height_step = StateMatrixHeightDerivative(model, height_m, speed_mps);
    result.height_derivatives =
        InModalOrder(result.modal, match, EigenvalueDerivatives(system, result.height_step.dA_dH));
    result.margin_height_derivative_per_s_per_m = margin_of(result.height_derivatives);
  }

  for (const auto& p : parameters) {
    ParameterEigenSensitivity row;
    row.parameter = p;
    row.value = ParameterValue(model, speed_mps, p);
    row.method = StateMatrixDerivativeMethod(model, p);
    const Matrix5d dA = StateMatrixDerivative(model, height_m, speed_mps, p);
    // A parameter outside Eq. (1) leaves A bitwise unchanged, so its difference is exactly zero.
    row.enters_state_matrix = dA.cwiseAbs().maxCoeff() != 0.0;
    row.eigenvalue_derivatives = InModalOrder(result.modal, match, EigenvalueDerivatives(system, dA));
    row.margin_derivative = margin_of(row.eigenvalue_derivatives);
    result.parameters.push_back(row);
  }
  return result;
}

double CriterionDirectionalDerivative(const Matrix5d& A, const Matrix5d& dA, bool hopf, bool deflated) {
  // Complex step: c(A + i·h·dA) = c(A) + i·h·∂c·dA + O(h²) with no subtraction, so h can be tiny.
  constexpr double kStep = 1e-30;
  using Complex = std::complex<double>;
  const Eigen::Matrix<Complex, 5, 5> Z = A.cast<Complex>() + Complex(0.0, kStep) * dA.cast<Complex>();
  const std::array<Complex, 6> a = FaddeevLeVerrier<Complex>(Z);
  Complex c;
  if (hopf) {
    c = deflated ? HurwitzDelta3(a) : HurwitzDelta4(a);
  } else {
    c = deflated ? a[4] : a[5];
  }
  return c.imag() / kStep;
}

double ImplicitBoundaryDerivative(const Matrix5d& A, const Matrix5d& dA_dp, const Matrix5d& dA_dH, bool hopf,
                                  bool deflated) {
  return -CriterionDirectionalDerivative(A, dA_dp, hopf, deflated) /
         CriterionDirectionalDerivative(A, dA_dH, hopf, deflated);
}

std::string HeightDerivativeUnit(const ModelParameter& p) {
  const std::string unit(p.Unit());
  if (unit == "1") return "m";
  // A compound unit goes in parentheses: "m/(kg m^2)", "m/(m/s)".
  return unit.find_first_of(" /") == std::string::npos ? "m/" + unit : "m/(" + unit + ")";
}

BoundarySensitivities ComputeBoundarySensitivities(const LongitudinalModel& model,
                                                   const BoundaryResult& boundary,
                                                   const std::vector<ModelParameter>& parameters) {
  BoundarySensitivities result;
  result.speed_mps = boundary.speed_mps;
  if (!boundary.height_m) {
    result.reason = "no boundary: " + boundary.reason;
    return result;
  }
  result.height_m = *boundary.height_m;
  result.eigen = ComputeEigenSensitivities(model, result.height_m, boundary.speed_mps, parameters);
  const int m = result.eigen.margin_index;
  if (m < 0) {
    result.reason = "no eigenvalue sets the stability margin at H* (non-finite A, or all neutral)";
    return result;
  }
  result.mode = m < 2 ? "short_period" : (m < 4 ? "phugoid" : "height");
  result.margin_height_derivative_per_s_per_m = result.eigen.margin_height_derivative_per_s_per_m;
  if (!std::isfinite(result.margin_height_derivative_per_s_per_m) ||
      result.margin_height_derivative_per_s_per_m == 0.0) {
    result.reason =
        "the stability margin is stationary in H at H* (dσ/dH = 0): H* does not move to first order";
    return result;
  }
  result.valid = true;
  // The boundary's crossing, for the implicit-function form.
  const BoundaryCrossing* crossing = nullptr;
  for (const auto& c : boundary.crossings) {
    if (c.height_m == result.height_m && (c.kind == CrossingKind::kHopf || c.kind == CrossingKind::kReal))
      crossing = &c;
  }
  const Matrix5d A = model.StateMatrix(result.height_m, boundary.speed_mps);
  for (const auto& row : result.eigen.parameters) {
    BoundaryParameterSensitivity s;
    s.parameter = row.parameter;
    s.value = row.value;
    s.margin_derivative = row.margin_derivative;
    s.height_derivative = -row.margin_derivative / result.margin_height_derivative_per_s_per_m;
    s.relative_height_derivative_m = row.value * s.height_derivative;
    if (crossing && row.enters_state_matrix) {
      s.implicit_height_derivative = ImplicitBoundaryDerivative(
          A, StateMatrixDerivative(model, result.height_m, boundary.speed_mps, row.parameter),
          result.eigen.height_step.dA_dH, crossing->kind == CrossingKind::kHopf, crossing->deflated);
    } else if (!row.enters_state_matrix) {
      s.implicit_height_derivative = 0.0;
    }
    s.enters_state_matrix = row.enters_state_matrix;
    s.method = row.method;
    result.parameters.push_back(s);
  }
  return result;
}

std::vector<BoundaryParameterSensitivity> RankByRelativeEffect(const BoundarySensitivities& sensitivities) {
  std::vector<BoundaryParameterSensitivity> ranked;
  for (const auto& s : sensitivities.parameters) {
    if (s.enters_state_matrix) ranked.push_back(s);
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return std::abs(a.relative_height_derivative_m) > std::abs(b.relative_height_derivative_m);
  });
  return ranked;
}

}  // namespace gesweep
