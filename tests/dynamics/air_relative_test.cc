// Eq. (1) in air-relative form (docs/model.md §9): still air is today's path to the bit, the wind
// terms equal a rearrangement of the matrix form A·x_a + B·δe, and a steady headwind has its
// equilibrium at Δu = −W with the derivatives at the airspeed u0.
#include <gtest/gtest.h>

#include <random>

#include "engine/dynamics/longitudinal_model.h"
#include "engine/simulation/derivative_kernel.h"
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
      for (int k = 0; k < 5; ++k) EXPECT_NEAR(actual[k], expected[k], kTolerance * (1 + std::abs(expected[k]))) << k;
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

}  // namespace
}  // namespace gesweep
