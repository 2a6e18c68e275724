#pragma once
/// First-order perturbation of the eigenvalues of a real matrix (docs/sensitivity.md, "Local
/// sensitivities"): for a simple eigenvalue λ with right eigenvector x (A x = λ x) and left
/// eigenvector y (yᴴ A = λ yᴴ), dλ = yᴴ (dA) x / (yᴴ x).

#include <Eigen/Core>

namespace gesweep {

/// The eigenvalues of a real square matrix with matched right and left eigenvectors.
struct EigenSystem {
  Eigen::VectorXcd eigenvalues;  ///< λ_i, in the order of Eigen::EigenSolver on A
  Eigen::MatrixXcd right;        ///< column i: x_i with A x_i = λ_i x_i
  /// Column i: y_i with y_iᴴ A = λ_i y_iᴴ, the eigenvector of Aᵀ for conj(λ_i), matched by eigenvalue.
  Eigen::MatrixXcd left;
  /// Wilkinson's condition number ‖x_i‖ ‖y_i‖ / |y_iᴴ x_i| ≥ 1: the amplification of a perturbation of
  /// A into λ_i. +∞ (and derivatives meaningless) when the eigenvalue is defective.
  Eigen::VectorXd condition_numbers;
  /// |conj(λ_i) − μ| for the eigenvalue μ of Aᵀ matched to λ_i: rounding-level unless the eigenvalues
  /// are (nearly) repeated, where the matching, and the derivative, are ill-defined.
  Eigen::VectorXd match_distances;
  bool finite = true;  ///< false when A had a non-finite entry; then every field is NaN
};

/// Eigen-decomposes A and Aᵀ with Eigen::EigenSolver and pairs each eigenvalue of A with the closest
/// unused eigenvalue conj-mirrored from Aᵀ (closest pairs first). Precondition: A square, non-empty.
EigenSystem ComputeEigenSystem(const Eigen::MatrixXd& A);

/// dλ_i/dp = y_iᴴ (∂A/∂p) x_i / (y_iᴴ x_i) for every eigenvalue of `system`, in its order.
/// Precondition: dA_dp has the size of the decomposed matrix.
Eigen::VectorXcd EigenvalueDerivatives(const EigenSystem& system, const Eigen::MatrixXd& dA_dp);

}  // namespace gesweep
