#include "engine/estimators/eigen_sensitivity.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "engine/common/errors.h"

namespace gesweep {

EigenSystem ComputeEigenSystem(const Eigen::MatrixXd& A) {
  GESWEEP_DEMAND(A.rows() == A.cols() && A.rows() > 0);
  const Eigen::Index n = A.rows();
  EigenSystem system;
  if (!A.allFinite()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    system.finite = false;
    system.eigenvalues = Eigen::VectorXcd::Constant(n, {nan, nan});
    system.right = Eigen::MatrixXcd::Constant(n, n, {nan, nan});
    system.left = system.right;
    system.condition_numbers = Eigen::VectorXd::Constant(n, nan);
    system.match_distances = system.condition_numbers;
    return system;
  }
  const Eigen::EigenSolver<Eigen::MatrixXd> right_solver(A);
  const Eigen::MatrixXd At = A.transpose();
  const Eigen::EigenSolver<Eigen::MatrixXd> left_solver(At);
  system.eigenvalues = right_solver.eigenvalues();
  system.right = right_solver.eigenvectors();
  const Eigen::VectorXcd& mirrored = left_solver.eigenvalues();
  const Eigen::MatrixXcd transposed_vectors = left_solver.eigenvectors();

  // Aᵀ z = μ z with μ = conj(λ) is zᴴ A = λ zᴴ: z is the left eigenvector of λ.
  std::vector<std::tuple<double, Eigen::Index, Eigen::Index>> candidates;
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index k = 0; k < n; ++k) {
      candidates.emplace_back(std::abs(std::conj(system.eigenvalues[i]) - mirrored[k]), i, k);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> right_taken(n, false), left_taken(n, false);
  system.left.resize(n, n);
  system.match_distances.resize(n);
  for (const auto& [distance, i, k] : candidates) {
    if (right_taken[i] || left_taken[k]) continue;
    right_taken[i] = left_taken[k] = true;
    system.left.col(i) = transposed_vectors.col(k);
    system.match_distances[i] = distance;
  }
  system.condition_numbers.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double overlap = std::abs(system.left.col(i).dot(system.right.col(i)));  // |yᴴ x|
    system.condition_numbers[i] = overlap > 0.0
                                      ? system.left.col(i).norm() * system.right.col(i).norm() / overlap
                                      : std::numeric_limits<double>::infinity();
  }
  return system;
}

Eigen::VectorXcd EigenvalueDerivatives(const EigenSystem& system, const Eigen::MatrixXd& dA_dp) {
  const Eigen::Index n = system.eigenvalues.size();
  GESWEEP_DEMAND(dA_dp.rows() == n && dA_dp.cols() == n);
  const Eigen::MatrixXcd dA = dA_dp.cast<std::complex<double>>();
  Eigen::VectorXcd derivatives(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto x = system.right.col(i);
    const auto y = system.left.col(i);
    // Eigen's dot conjugates its first argument: y.dot(v) = yᴴ v.
    derivatives[i] = y.dot(dA * x) / y.dot(x);
  }
  return derivatives;
}

}  // namespace gesweep
