#pragma once
/// The linear longitudinal model of docs/model.md §4–§5: the dimensional derivatives of the paper's
/// Table 1 and the 5-state matrices A, B of its Eq. (1), at any height and speed.

#include <Eigen/Core>

#include "engine/aircraft/aircraft.h"
#include "engine/aircraft/atmosphere.h"
#include "engine/dynamics/coefficient_table.h"
#include "engine/dynamics/model_options.h"

namespace gesweep {

using Matrix5d = Eigen::Matrix<double, 5, 5>;
using Vector5d = Eigen::Matrix<double, 5, 1>;

/// State indices of x = [Δu, Δw, q, Δθ, ΔH] (docs/model.md §1).
enum StateIndex : int { kDeltaU = 0, kDeltaW = 1, kPitchRate = 2, kDeltaTheta = 3, kDeltaH = 4 };
inline constexpr int kStateCount = 5;

/// Dimensional stability derivatives (paper's Table 1; docs/model.md §4). X and Z in m/s² per unit of
/// the state they multiply, M in rad/s² per unit; Xh, Zh, Mh per metre of ΔH.
struct DimensionalDerivatives {
  double Xu = 0, Xw = 0, Xh = 0, Xde = 0;
  double Zu = 0, Zw = 0, Zh = 0, Zde = 0;
  double Mu = 0, Mw = 0, Mw_dot = 0, Mq = 0, Mh = 0, Mde = 0;
};

/// Mass and geometry that the derivatives use (after any sweep overrides).
struct MassGeometry {
  double mass_kg = 0;
  double pitch_inertia_kgm2 = 0;
  double mean_chord_m = 0;
  double wing_area_m2 = 0;
  double CDo = 0, CDu = 0, CLu = 0, CMu = 0, CDde = 0;
};

/// Table 1 of the paper, evaluated for one coefficient row, density ρ (kg/m³) and speed u (m/s):
/// Q = ½ρu². Pure function; the h-derivatives are included.
DimensionalDerivatives ComputeDerivatives(const CoefficientRow& coefficients, const MassGeometry& mg,
                                          double density_kgpm3, double speed_mps);

/// Eq. (1): A from the derivatives and the kinematic reference speed u0 (row Δw col q; row ΔH col Δθ).
Matrix5d AssembleStateMatrix(const DimensionalDerivatives& d, double reference_speed_mps);
/// Eq. (1): B, the elevator column [Xδe, Zδe, Mδe + Mẇ·Zδe, 0, 0].
Vector5d AssembleInputMatrix(const DimensionalDerivatives& d);

/// The air's motion at the airplane, the extra inputs of Eq. (1) in air-relative form
/// (docs/model.md §9): u_g along x (positive forward: a headwind is negative), w_g along z (positive
/// down), the pitch-rate gust q_g, and ẇ_g, the rate of w_g along the flight path. Zero: still air.
struct AirVelocity {
  double u_g_mps = 0;
  double w_g_mps = 0;
  double q_g_radps = 0;
  double w_g_dot_mps2 = 0;
};

/// Eq. (1) in air-relative form (docs/model.md §9): the aerodynamic terms act on Δu_a = Δu − u_g,
/// Δw_a = Δw − w_g (and Mq on q − q_g, Mẇ on Δẇ − ẇ_g); the kinematic terms u0·q, q and
/// u0·Δθ − Δw keep the inertial velocities. d are the derivatives at the current H and airspeed,
/// u0 the kinematic reference speed. With AirVelocity{} the result is ẋ = A x + B δe, computed by
/// the same operations as Equation1Derivative of engine/simulation/derivative_kernel.h.
/// Inline: it is on every right-hand side of a landing in a moving atmosphere.
inline Vector5d AirRelativeDerivative(const DimensionalDerivatives& d, double u0, const Vector5d& x,
                                      double elevator_rad, const AirVelocity& air) {
  // Written in the order of Equation1Derivative (derivative_kernel.h) so that still air gives the
  // same doubles: Δu − 0 and Δw − 0 are exact, and the gust terms of row q are added only when present.
  const double du_a = x[kDeltaU] - air.u_g_mps;
  const double dw_a = x[kDeltaW] - air.w_g_mps;
  const double q = x[kPitchRate], dtheta = x[kDeltaTheta], dh = x[kDeltaH];
  const double m_u = d.Mu + d.Mw_dot * d.Zu;
  const double m_w = d.Mw + d.Mw_dot * d.Zw;
  const double m_q = d.Mq + d.Mw_dot * u0;
  const double m_h = d.Mh + d.Mw_dot * d.Zh;
  const double m_de = d.Mde + d.Mw_dot * d.Zde;
  Vector5d dxdt;
  dxdt[kDeltaU] = d.Xu * du_a + d.Xw * dw_a - kGravity_mps2 * dtheta + d.Xh * dh + d.Xde * elevator_rad;
  dxdt[kDeltaW] = d.Zu * du_a + d.Zw * dw_a + u0 * q + d.Zh * dh + d.Zde * elevator_rad;
  dxdt[kPitchRate] = m_u * du_a + m_w * dw_a + m_q * q + m_h * dh + m_de * elevator_rad;
  if (air.q_g_radps != 0.0 || air.w_g_dot_mps2 != 0.0) {
    dxdt[kPitchRate] -= d.Mq * air.q_g_radps + d.Mw_dot * air.w_g_dot_mps2;
  }
  dxdt[kDeltaTheta] = q;
  dxdt[kDeltaH] = -x[kDeltaW] + u0 * dtheta;
  return dxdt;
}

/// One aircraft under one set of model options.
class LongitudinalModel {
 public:
  /// Throws InputError when the options do not apply (see CoefficientTable) or overrides are not > 0.
  LongitudinalModel(Aircraft aircraft, const ModelOptions& options);

  const Aircraft& aircraft() const { return aircraft_; }
  const ModelOptions& options() const { return options_; }
  const CoefficientTable& table() const { return table_; }
  const MassGeometry& mass_geometry() const { return mass_geometry_; }

  /// Coefficients at height H, m (docs/model.md §2).
  CoefficientRow CoefficientsAt(double height_m) const { return table_.At(height_m); }
  /// ISA density at field elevation + H, kg/m³ (sea-level density for H = ∞).
  double DensityAt(double height_m) const;
  /// Derivatives at height H and speed u; Xh = Zh = Mh = 0 when h-derivatives are off.
  DimensionalDerivatives DerivativesAt(double height_m, double speed_mps) const;
  /// A of Eq. (1) at H, with the derivatives at speed u and the kinematic entries at u.
  Matrix5d StateMatrix(double height_m, double speed_mps) const;
  /// B of Eq. (1) at H and u.
  Vector5d InputMatrix(double height_m, double speed_mps) const;
  /// ẋ of Eq. (1) at state x (SI), elevator δe (rad) and air motion `air`, with the derivatives
  /// re-evaluated (docs/model.md §7, §9) at H = H0 + ΔH and the airspeed u0 + Δu − u_g, and the
  /// kinematic entries at the reference u0. Still air gives the open-loop run's generic path exactly.
  Vector5d StateDerivative(double start_height_m, double reference_speed_mps, const Vector5d& x,
                           double elevator_rad, const AirVelocity& air = {}) const;

 private:
  Aircraft aircraft_;
  ModelOptions options_;
  CoefficientTable table_;
  MassGeometry mass_geometry_;
};

}  // namespace gesweep
