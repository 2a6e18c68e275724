// The landing controller's design model (docs/landing.md §2): why the paper's 9-state system cannot be
// designed on, why the 8-state model is its controllable part, and that the default gain stabilises it.
#include "engine/control/landing_design.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

/// Structural identities hold to rounding of entries of size ≤ u0 ≈ 52.
constexpr double kStructureTolerance = 1e-12;
/// Relative CARE residual of an 8-state SB02OD solve with entries spanning 1e-5 … 1e2.
constexpr double kRelativeResidualTolerance = 1e-8;

LongitudinalModel Ance(bool h_derivatives = true) {
  ModelOptions options;
  options.h_derivatives = h_derivatives;
  return LongitudinalModel(LoadAircraftFile(testing::AnceAircraftPath()), options);
}

TEST(LandingDesign, PaperNineStateSystemIsNotStabilizable) {
  // ΔH and d integrate the same signal u0·Δθ − Δw: the row vector e_ΔH − e_d annihilates A and B, so
  // λ = 0 is an uncontrollable eigenvalue, in and out of ground effect.
  const LongitudinalModel model = Ance();
  for (double height_m : {0.788, 2.0, 500.0}) {
    Eigen::MatrixXd A, B;
    BuildAugmentedSystem(model.DerivativesAt(height_m, 52.21), 52.21, 10.0, 10.0, A, B);
    Eigen::RowVectorXd w = Eigen::RowVectorXd::Zero(kLandingStateCount);
    w(4) = 1.0;
    w(6) = -1.0;
    EXPECT_LT((w * A).norm(), kStructureTolerance);
    EXPECT_LT((w * B).norm(), kStructureTolerance);
    const LqrResult lqr = Lqr(A, B, Eigen::MatrixXd::Identity(9, 9), Eigen::MatrixXd::Identity(1, 1));
    EXPECT_EQ(lqr.status, RiccatiStatus::kNotStabilizable) << "H = " << height_m << ": " << lqr.message;
  }
}

TEST(LandingDesign, DesignModelIsTheNineStateSystemOnTheSubspaceDeltaHEqualsD) {
  // C maps ζ into the subspace ΔH = d of Eq. (14); the subspace is invariant and the 8-state model is the
  // 9-state model restricted to it: A9·C = C·A8 and B9 = C·B8.
  const LongitudinalModel model = Ance();
  const DimensionalDerivatives d = model.DerivativesAt(0.788, 52.21);
  Eigen::MatrixXd A9, B9;
  BuildAugmentedSystem(d, 52.21, 10.0, 10.0, A9, B9);
  const LandingDesignModel m = BuildLandingDesignModel(d, 52.21, 10.0, 10.0);
  EXPECT_LT((A9 * m.C - m.C * m.A).norm(), kStructureTolerance);
  EXPECT_LT((B9 - m.C * m.B).norm(), kStructureTolerance);
  // And the reduced model is controllable where the full one is not.
  EXPECT_TRUE(CheckStabilizable(m.A, m.B).holds);
}

TEST(LandingDesign, DefaultGainStabilisesTheDesignModel) {
  const LongitudinalModel model = Ance();
  const LandingConfig config;
  const LandingDesign design = DesignLandingController(model, config);
  ASSERT_TRUE(design.ok()) << design.message;
  EXPECT_DOUBLE_EQ(design.design_height_m, model.aircraft().wheel_contact_height_m);
  EXPECT_DOUBLE_EQ(design.design_speed_mps, config.start_speed_mps);
  EXPECT_EQ(design.gain[4], 0.0);  // no feedback of ΔH, the reference trajectory's own height
  // Closed-loop eigenvalues recomputed here from the model and the gain, not taken from the solver.
  const DesignMatrix closed = design.model.A - design.model.B * design.design_gain;
  const Eigen::VectorXcd eigenvalues = Eigen::EigenSolver<DesignMatrix>(closed).eigenvalues();
  for (Eigen::Index i = 0; i < eigenvalues.size(); ++i)
    EXPECT_LT(eigenvalues(i).real(), 0.0) << eigenvalues(i);
  // The open-loop design model is unstable at the wheel-contact height (the ground-effect phugoid,
  // docs/model.md §6), so this is a real stabilisation, not a formality.
  const Eigen::VectorXcd open = Eigen::EigenSolver<DesignMatrix>(design.model.A).eigenvalues();
  EXPECT_GT(open.real().maxCoeff(), 0.0);
  // The gain is the LQR gain of lqry's weights: check the CARE residual with Q̄ = CᵀQC written out.
  const Eigen::MatrixXd Q = design.model.C.transpose() * design.model.C;  // identity output weights
  const Eigen::MatrixXd& S = design.riccati_solution;
  const Eigen::MatrixXd A = design.model.A;
  const Eigen::MatrixXd B = design.model.B;
  const Eigen::MatrixXd residual =
      A.transpose() * S + S * A - S * B * B.transpose() * S / config.r_weight + Q;
  EXPECT_LT(residual.norm() / (2 * (A.transpose() * S).norm() + Q.norm()), kRelativeResidualTolerance);
  EXPECT_LT((design.design_gain - B.transpose() * S / config.r_weight).norm(),
            1e-9 * design.design_gain.norm());
}

TEST(LandingDesign, DeltaHWeightAddsToTheDeviationWeight) {
  // In the design model ΔH and d are one state, so weighting ΔH by a and d by b is weighting e by a + b.
  const LongitudinalModel model = Ance();
  LandingConfig split;
  split.q_weights = {1, 1, 1, 1, 0.5, 1, 1.5, 1, 1};
  LandingConfig merged;
  merged.q_weights = {1, 1, 1, 1, 0, 1, 2, 1, 1};
  const LandingDesign a = DesignLandingController(model, split);
  const LandingDesign b = DesignLandingController(model, merged);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_LT((a.design_gain - b.design_gain).norm(), 1e-9 * b.design_gain.norm());
}

TEST(LandingDesign, UnweightedUnstableDesignFailsCleanly) {
  // With Q = 0 the unstable ground-effect phugoid of the design model is undetectable: no stabilising
  // optimal gain exists, and the design says so instead of returning one.
  const LongitudinalModel model = Ance();
  LandingConfig config;
  config.q_weights.fill(0.0);
  const LandingDesign design = DesignLandingController(model, config);
  EXPECT_EQ(design.status, RiccatiStatus::kNotDetectable) << design.message;
  EXPECT_FALSE(design.message.empty());
}

TEST(LandingDesign, DesignHeightDerivativesFollowTheDesignOptionNotThePlant) {
  // The plant model without h-derivatives still designs with them unless told otherwise.
  const LongitudinalModel without = Ance(false);
  const LandingDesign with_h = DesignLandingController(without, LandingConfig{});
  LandingConfig no_h;
  no_h.design_h_derivatives = false;
  const LandingDesign without_h = DesignLandingController(without, no_h);
  const double zh = ComputeDerivatives(without.CoefficientsAt(0.788), without.mass_geometry(),
                                       without.DensityAt(0.788), 52.21)
                        .Zh;
  EXPECT_NE(zh, 0.0);
  EXPECT_NEAR(with_h.model.A(kDesignDeltaW, kDesignTrackingError), zh, kStructureTolerance);
  EXPECT_EQ(without_h.model.A(kDesignDeltaW, kDesignTrackingError), 0.0);
}

// The thread's cache of LQR solutions (DesignCache::kUse) returns what Lqry computes, bit for bit, and
// never a stale one: each input of the design changed alone (with designs in between that fill and
// cycle the cache) gives the solution solved afresh. The oracle is the uncached design (kSolve).
void ExpectSameDesign(const LandingDesign& cached, const LandingDesign& solved, const std::string& what) {
  ASSERT_EQ(cached.status, solved.status) << what;
  EXPECT_EQ(cached.message, solved.message) << what;
  for (std::size_t i = 0; i < cached.gain.size(); ++i)
    EXPECT_EQ(std::bit_cast<std::uint64_t>(cached.gain[i]), std::bit_cast<std::uint64_t>(solved.gain[i]))
        << what << ": gain " << i;
  EXPECT_EQ(cached.riccati_solution, solved.riccati_solution) << what;
  EXPECT_EQ(cached.closed_loop_eigenvalues, solved.closed_loop_eigenvalues) << what;
  EXPECT_EQ(std::bit_cast<std::uint64_t>(cached.closed_loop_max_real_per_s),
            std::bit_cast<std::uint64_t>(solved.closed_loop_max_real_per_s))
      << what;
}

TEST(LandingDesign, TheCachedSolutionIsTheSolvedOneForEveryInput) {
  const LongitudinalModel with_h = Ance(true);
  const LongitudinalModel without_h = Ance(false);
  std::vector<std::pair<std::string, LandingConfig>> configs;
  configs.emplace_back("default", LandingConfig{});
  auto changed = [&](const std::string& what, auto&& change) {
    LandingConfig c;
    change(c);
    configs.emplace_back(what, c);
  };
  changed("start speed", [](LandingConfig& c) { c.start_speed_mps = 55.0; });
  changed("design speed", [](LandingConfig& c) { c.design_speed_mps = 50.0; });
  changed("design height", [](LandingConfig& c) { c.design_height_m = 2.0; });
  changed("design without h-derivatives", [](LandingConfig& c) { c.design_h_derivatives = false; });
  changed("actuator pole", [](LandingConfig& c) { c.actuator_pole_per_s = 12.0; });
  changed("compensator pole", [](LandingConfig& c) { c.compensator_pole_per_s = 8.0; });
  changed("r", [](LandingConfig& c) { c.r_weight = 2.0; });
  for (std::size_t i = 0; i < kLandingStateCount; ++i)
    changed("q " + std::to_string(i), [i](LandingConfig& c) { c.q_weights[i] = 3.0; });
  changed("no q (a failed design)", [](LandingConfig& c) { c.q_weights.fill(0.0); });
  changed("start speed by one ulp",
          [](LandingConfig& c) { c.start_speed_mps = std::nextafter(c.start_speed_mps, 100.0); });
  ASSERT_GT(configs.size(), 2 * kLandingDesignCacheSize);  // the cache is filled and cycled
  // Twice over, so the second round finds designs that were cached and some that were evicted.
  for (int round = 0; round < 2; ++round) {
    for (const auto& [what, config] : configs) {
      for (const LongitudinalModel* model : {&with_h, &without_h}) {
        const std::string where = what + (model == &with_h ? "" : ", plant without h-derivatives") +
                                  ", round " + std::to_string(round);
        ExpectSameDesign(DesignLandingController(*model, config),
                         DesignLandingController(*model, config, DesignCache::kSolve), where);
      }
    }
  }
}

}  // namespace
}  // namespace gesweep
