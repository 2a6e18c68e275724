// Eq. (1) in air-relative form (docs/model.md §9): still air is today's path to the bit, the wind
// terms equal a rearrangement of the matrix form A·x_a + B·δe, and a steady headwind has its
// equilibrium at Δu = −W with the derivatives at the airspeed u0.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>

#include "engine/dynamics/longitudinal_model.h"
#include "engine/simulation/derivative_kernel.h"
#include "engine/simulation/integrator.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

const LongitudinalModel& Model() {
  static const LongitudinalModel model(LoadAircraftFile(testing::AnceAircraftPath()), ModelOptions{});
  return model;
}

Vector5d RandomState(std::mt19937& rng) {
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  return Vector5d(3 * d(rng), 2 * d(rng), 0.2 * d(rng), 0.1 * d(rng), 1.5 * d(rng));
}

TEST(AirRelative, StillAirIsTheGenericPathBitForBit) {
  // Today's generic path of the open-loop run (ModelSource in open_loop.cc): derivatives at
  // (H0 + ΔH, u0 + Δu), then Equation1Derivative with the kinematic u0.
  std::mt19937 rng(7);
  const double u0 = 32.0208;
  for (double h0 : {0.9, 1.5561, 2.9987, 5.5922, 40.0}) {
    for (int i = 0; i < 50; ++i) {
      const Vector5d x = RandomState(rng);
      const double elevator = 0.05 * (i % 3 - 1);
      const DimensionalDerivatives d = Model().DerivativesAt(h0 + x[kDeltaH], u0 + x[kDeltaU]);
      double today[5];
      Equation1Derivative(EntriesFromDerivatives(d, u0), u0, x.data(), elevator, today);
      const Vector5d now = Model().StateDerivative(h0, u0, x, elevator);
      for (int k = 0; k < 5; ++k) EXPECT_EQ(now[k], today[k]) << "h0 " << h0 << " i " << i << " k " << k;
    }
  }
}

TEST(AirRelative, WindTermsEqualTheRearrangedMatrixForm) {
  // ẋ = A·x_a + B·δe + k, x_a = [Δu − u_g, Δw − w_g, q − q_g, Δθ, ΔH], with A, B at (H, u0 + Δu_a)
  // and the kinematic corrections k that restore the inertial velocities (derived by hand):
  //   row Δw: + u0·q_g;  row q: + Mẇ·u0·q_g − Mẇ·ẇ_g;  row Δθ: + q_g;  row ΔH: − w_g.
  constexpr double kTolerance = 1e-12;  // the same sums in another order
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> g(-3.0, 3.0);
  const double u0 = 32.0208;
  for (double h0 : {1.2, 2.5935, 30.0}) {
    for (int i = 0; i < 30; ++i) {
      const Vector5d x = RandomState(rng);
      const AirVelocity air{g(rng), g(rng), 0.05 * g(rng), 2 * g(rng)};
      const double elevator = 0.03;
      const double airspeed = u0 + x[kDeltaU] - air.u_g_mps;
      const DimensionalDerivatives d = Model().DerivativesAt(h0 + x[kDeltaH], airspeed);
      Vector5d xa = x;
      xa[kDeltaU] -= air.u_g_mps;
      xa[kDeltaW] -= air.w_g_mps;
      xa[kPitchRate] -= air.q_g_radps;
      Vector5d expected = AssembleStateMatrix(d, u0) * xa + AssembleInputMatrix(d) * elevator;
      expected[kDeltaW] += u0 * air.q_g_radps;
      expected[kPitchRate] += d.Mw_dot * u0 * air.q_g_radps - d.Mw_dot * air.w_g_dot_mps2;
      expected[kDeltaTheta] += air.q_g_radps;
      expected[kDeltaH] -= air.w_g_mps;
      const Vector5d actual = Model().StateDerivative(h0, u0, x, elevator, air);
      for (int k = 0; k < 5; ++k)
        EXPECT_NEAR(actual[k], expected[k], kTolerance * (1 + std::abs(expected[k]))) << k;
    }
  }
}

TEST(AirRelative, SteadyHeadwindEquilibrium) {
  // u_g = −W, Δu = −W: Δu_a = 0, so every aerodynamic term vanishes and the derivatives are taken at
  // the airspeed u0; the airplane flies on with the ground speed u0 − W.
  const double u0 = 32.0208, W = 7.717;
  for (double h0 : {1.5561, 2.5935, 50.0}) {
    Vector5d x = Vector5d::Zero();
    x[kDeltaU] = -W;
    const Vector5d dx = Model().StateDerivative(h0, u0, x, 0.0, AirVelocity{-W, 0, 0, 0});
    for (int k = 0; k < 5; ++k) EXPECT_EQ(dx[k], 0.0) << h0 << " " << k;
    // A tailwind start in the same headwind is not at rest: Δu_a = +W accelerates it back.
    x[kDeltaU] = 0.0;
    EXPECT_LT(Model().StateDerivative(h0, u0, x, 0.0, AirVelocity{-W, 0, 0, 0})[kDeltaU], 0.0);
  }
  // A steady vertical wind: the airplane moves with the air mass (ΔḢ = −w_g), no aerodynamic change.
  Vector5d x = Vector5d::Zero();
  x[kDeltaW] = -1.0;  // in a 1 m/s updraft
  const Vector5d dx = Model().StateDerivative(30.0, u0, x, 0.0, AirVelocity{0, -1.0, 0, 0});
  EXPECT_EQ(dx[kDeltaU], 0.0);
  EXPECT_EQ(dx[kPitchRate], 0.0);
  EXPECT_EQ(dx[kDeltaH], 1.0);
}

// The frozen linear model (derivatives fixed at H0, u0) flown through a 1 − cos vertical gust,
// w_g = (v/2)(1 − cos ωt), ω = π·u0/d_m, integrated by the engine's RK4.
struct FrozenInGust {
  static constexpr int kDimension = 5;
  static constexpr int kEventCount = 0;
  DimensionalDerivatives d;
  double u0, amplitude, omega;
  void Derivative(double t, const OdeState<5>& x, int, OdeState<5>& dxdt) {
    const AirVelocity air{0.0, 0.5 * amplitude * (1 - std::cos(omega * t)), 0.0,
                          0.5 * amplitude * omega * std::sin(omega * t)};
    const Vector5d v = AirRelativeDerivative(d, u0, Vector5d(x[0], x[1], x[2], x[3], x[4]), 0.0, air);
    for (int i = 0; i < 5; ++i) dxdt[i] = v[i];
  }
  void EventValues(double, const OdeState<5>&, int, std::array<double, 0>&) const {}
  EventAction OnEvent(int, double, const OdeState<5>&, int) { return EventAction::kContinue; }
  void OnStep(double, const OdeState<5>&, int) {}
  void OnOutput(double, const OdeState<5>&, int) {}
};

TEST(AirRelative, FrozenModelGustResponseIsTheMatrixExponential) {
  // Closed form: the gust is the output of the exosystem c' = 0, C' = −ωS, S' = ωC (c = 1, C = cos ωt,
  // S = sin ωt), w_g = (v/2)(c − C), ẇ_g = (v/2)ωS. With E_w = −[Xw, Zw, Mw + Mẇ·Zw, 0, 0] (the
  // aerodynamic Δw_a terms of docs/model.md §9) and E_ẇ = [0, 0, −Mẇ, 0, 0], the augmented state
  // [x; c; C; S] obeys z' = M z, so x(t) = first five entries of exp(M t)·[0; 1; 1; 0].
  const double h0 = 2.5935, u0 = 32.0208, amplitude = 1.5, half_length = 15.0;
  const double omega = std::numbers::pi * u0 / half_length;
  const DimensionalDerivatives d = Model().DerivativesAt(h0, u0);
  Eigen::Matrix<double, 8, 8> M = Eigen::Matrix<double, 8, 8>::Zero();
  M.topLeftCorner<5, 5>() = AssembleStateMatrix(d, u0);
  const Vector5d e_w(-d.Xw, -d.Zw, -(d.Mw + d.Mw_dot * d.Zw), 0, 0);
  const Vector5d e_wdot(0, 0, -d.Mw_dot, 0, 0);
  M.block<5, 1>(0, 5) = 0.5 * amplitude * e_w;
  M.block<5, 1>(0, 6) = -0.5 * amplitude * e_w;
  M.block<5, 1>(0, 7) = 0.5 * amplitude * omega * e_wdot;
  M(6, 7) = -omega;
  M(7, 6) = omega;
  Eigen::Matrix<double, 8, 1> z0 = Eigen::Matrix<double, 8, 1>::Zero();
  z0[5] = z0[6] = 1.0;
  const double end_s = 2 * half_length / u0;  // the whole bump
  FrozenInGust problem{d, u0, amplitude, omega};
  IntegratorOptions io;
  io.step_s = 1e-3;
  const auto r = Integrate(problem, OdeState<5>{}, 0.0, end_s, {}, io);
  const Eigen::Matrix<double, 8, 1> z = (M * end_s).exp() * z0;
  // RK4 at h = 1 ms against the exact solution: global error ~ (λ_max h)⁴ ≈ 1e-11 relative.
  constexpr double kTolerance = 1e-9;
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(r.final_state[i], z[i], kTolerance * (1 + std::abs(z[i]))) << i;
  }
  EXPECT_GT(std::abs(z[kDeltaW]), 0.1) << "the gust must move the airplane";
}

}  // namespace
}  // namespace gesweep
