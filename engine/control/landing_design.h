#pragma once
/// The LQR design of the landing controller (docs/model.md §8; paper Eq. (14)–(21), (29)).
///
/// The paper's augmented glide-slope state is z = [Δu, Δw, q, Δθ, ΔH, δe, d, x_d, ε_d] (Eq. (14)). Its
/// system (Eq. (16)) is not stabilisable: ΔH and d both integrate u0·Δθ − Δw, so ΔH − d is a zero
/// eigenvalue that no input moves, and no stabilising Riccati solution exists (a test shows it). The
/// design is therefore done on the 8-state model
///     ζ = [Δu, Δw, q, Δθ, δe, e, x_c, ε_c]
/// in which the height perturbation about the reference trajectory is one state e (e = d on the glide
/// path, e = H − H_ref in the flare): the ΔH column of Eq. (1) (Xh, Zh, Mh + Mẇ·Zh) acts on e. This is
/// exactly the controllable part of Eq. (16) after the change of coordinates ΔH ↦ ΔH − d; the dropped
/// coordinate is the height of the reference trajectory itself, which the controller must not feed back
/// (a gain on it would command the elevator in proportion to the height above ground). The paper's 9 gains
/// follow with K_ΔH = 0, and the paper's identity output weight maps onto ζ through y = Cζ (lqry).
/// docs/landing.md §2 has the derivation.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <limits>
#include <string>

#include "engine/control/landing_config.h"
#include "engine/control/riccati.h"
#include "engine/dynamics/longitudinal_model.h"

namespace gesweep {

/// Number of states of the design model ζ.
inline constexpr int kDesignStateCount = 8;

/// Indices of ζ.
enum DesignStateIndex : int {
  kDesignDeltaU = 0,
  kDesignDeltaW = 1,
  kDesignPitchRate = 2,
  kDesignDeltaTheta = 3,
  kDesignElevator = 4,
  kDesignTrackingError = 5,  ///< e: d before the flare, H − H_ref after it, m
  kDesignCompensator = 6,    ///< x_c of Tf2, m·s
  kDesignErrorIntegral = 7,  ///< ε_c of Tf1, ∫(r − e) dt, m·s
};

using DesignMatrix = Eigen::Matrix<double, kDesignStateCount, kDesignStateCount>;
using DesignVector = Eigen::Matrix<double, kDesignStateCount, 1>;
/// Maps ζ to the 9 states of Eq. (14) (ΔH and d both read e).
using DesignOutputMap = Eigen::Matrix<double, kLandingStateCount, kDesignStateCount>;

/// ζ̇ = Aζ + Bηe (exogenous inputs −u0·γr or H_ref/τ and the reference r = 0 left out), y = Cζ.
struct LandingDesignModel {
  DesignMatrix A;
  DesignVector B;
  DesignOutputMap C;
};

/// The design model from the derivatives d at the design point and the kinematic speed u0 (m/s), with
/// actuator pole Sδ and compensator pole S_d (1/s).
LandingDesignModel BuildLandingDesignModel(const DimensionalDerivatives& d, double reference_speed_mps,
                                           double actuator_pole_per_s, double compensator_pole_per_s);

/// The paper's 9-state augmented system of Eq. (16) (exogenous inputs left out): A 9×9, B 9×1 in the
/// state order of Eq. (14). Kept to document, and test, why the design is not done on it.
void BuildAugmentedSystem(const DimensionalDerivatives& d, double reference_speed_mps,
                          double actuator_pole_per_s, double compensator_pole_per_s, Eigen::MatrixXd& A,
                          Eigen::MatrixXd& B);

/// The result of the design: one constant gain for both phases.
struct LandingDesign {
  RiccatiStatus status = RiccatiStatus::kSolverFailed;
  std::string message;         ///< empty when ok
  double design_height_m = 0;  ///< what was used (config's or the default)
  double design_speed_mps = 0;
  bool design_h_derivatives = true;
  LandingDesignModel model;
  /// K on the states of Eq. (14), ηe = −K·z, K_ΔH = 0 (units: rad per unit of each state).
  std::array<double, kLandingStateCount> gain{};
  /// The design model's K on ζ, 1×8.
  Eigen::Matrix<double, 1, kDesignStateCount> design_gain =
      Eigen::Matrix<double, 1, kDesignStateCount>::Zero();
  /// Eigenvalues of A − BK of the design model, largest real part first (empty unless ok).
  Eigen::VectorXcd closed_loop_eigenvalues;
  /// The largest real part of closed_loop_eigenvalues, 1/s (NaN unless ok).
  double closed_loop_max_real_per_s = std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixXd riccati_solution;  ///< S (8×8), empty unless ok

  bool ok() const { return status == RiccatiStatus::kOk; }
};

/// How many LQR solutions a thread keeps (DesignCache::kUse): the designs of a sweep's few design points.
inline constexpr std::size_t kLandingDesignCacheSize = 8;

/// Whether a design may take the LQR solution of an earlier one of the same thread with the same
/// design model and weights, byte for byte (the solution is a pure function of them, so it is the one
/// Lqry would compute): kSolve always solves (the tests' reference).
enum class DesignCache { kUse, kSolve };

/// Designs K with Lqry on the design model at (design height, design speed) of `model`'s aircraft, with
/// the h-derivatives as config.design_h_derivatives says (whatever model.options() says). Never throws on
/// a numerical failure: the status says it. Precondition: config valid (ValidateLandingConfig).
LandingDesign DesignLandingController(const LongitudinalModel& model, const LandingConfig& config,
                                      DesignCache cache = DesignCache::kUse);

}  // namespace gesweep
