#include "engine/analysis/sensitivity_design.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

// The affine map to a range and back costs a few ulps of the range.
constexpr double kMapTolerance = 1e-12;

const std::vector<ParameterRange> kRanges = {{"a", 0.0, 1.0}, {"b", -2.0, 2.0}, {"c", 10.0, 30.0}};

TEST(SaltelliLayout, FollowsSalibsRowOrder) {
  const SaltelliLayout with{3, 4, true};
  EXPECT_EQ(with.BlockSize(), 8);  // 2D+2
  EXPECT_EQ(with.RowCount(), 32u);
  EXPECT_EQ(with.RowA(1), 8u);
  EXPECT_EQ(with.RowAB(1, 0), 9u);
  EXPECT_EQ(with.RowAB(1, 2), 11u);
  EXPECT_EQ(with.RowBA(1, 0), 12u);
  EXPECT_EQ(with.RowBA(1, 2), 14u);
  EXPECT_EQ(with.RowB(1), 15u);
  EXPECT_EQ(with.BlockOfRow(15), 1);
  EXPECT_EQ(with.BlockOfRow(16), 2);
  const SaltelliLayout without{3, 4, false};
  EXPECT_EQ(without.BlockSize(), 5);  // D+2
  EXPECT_EQ(without.RowB(0), 4u);
  EXPECT_EQ(without.RowAB(2, 1), 12u);
}

class SaltelliDesignRows : public ::testing::TestWithParam<bool> {};

TEST_P(SaltelliDesignRows, CrossSampleAAndBColumnByColumn) {
  const bool second_order = GetParam();
  const int N = 64;
  const Eigen::MatrixXd X = SaltelliDesign(kRanges, N, second_order);
  const SaltelliLayout layout{3, N, second_order};
  ASSERT_EQ(static_cast<std::size_t>(X.rows()), layout.RowCount());
  ASSERT_EQ(X.cols(), 3);
  for (int j = 0; j < N; ++j) {
    const auto a = X.row(static_cast<Eigen::Index>(layout.RowA(j)));
    const auto b = X.row(static_cast<Eigen::Index>(layout.RowB(j)));
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(X(static_cast<Eigen::Index>(layout.RowAB(j, i)), k), k == i ? b(k) : a(k));
        if (second_order) {
          EXPECT_EQ(X(static_cast<Eigen::Index>(layout.RowBA(j, i)), k), k == i ? a(k) : b(k));
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutSecondOrder, SaltelliDesignRows, ::testing::Bool());

TEST(SaltelliDesign, IsTheSobolSequenceMappedToTheRanges) {
  // The first points of the 6-dimensional Sobol sequence after the origin (Joe–Kuo direction numbers,
  // as in Boost): (1/2, …, 1/2), then coordinates 3/4 or 1/4 (Bratley & Fox 1988). Hand-mapped.
  const Eigen::MatrixXd X = SaltelliDesign(kRanges, 2, false);
  const SaltelliLayout layout{3, 2, false};
  for (int i = 0; i < 3; ++i) {
    const double mid = 0.5 * (kRanges[i].lower + kRanges[i].upper);
    EXPECT_NEAR(X(static_cast<Eigen::Index>(layout.RowA(0)), i), mid, kMapTolerance);
    EXPECT_NEAR(X(static_cast<Eigen::Index>(layout.RowB(0)), i), mid, kMapTolerance);
    const double second = (X(static_cast<Eigen::Index>(layout.RowA(1)), i) - kRanges[i].lower) /
                          (kRanges[i].upper - kRanges[i].lower);
    EXPECT_TRUE(std::abs(second - 0.25) < kMapTolerance || std::abs(second - 0.75) < kMapTolerance) << second;
  }
}

TEST(SaltelliDesign, FillsEachRangeEvenly) {
  // A (t, m, s)-net property of the Sobol sequence: every one-dimensional projection of 2^m points is
  // stratified, so each of 16 equal bins of each range gets N/16 points of A (± 1 for the skipped origin).
  const int N = 1024;
  const Eigen::MatrixXd X = SaltelliDesign(kRanges, N, false);
  const SaltelliLayout layout{3, N, false};
  for (int i = 0; i < 3; ++i) {
    std::vector<int> bins(16, 0);
    for (int j = 0; j < N; ++j) {
      const double x = X(static_cast<Eigen::Index>(layout.RowA(j)), i);
      ASSERT_GE(x, kRanges[i].lower);
      ASSERT_LT(x, kRanges[i].upper);
      ++bins[static_cast<int>(16 * (x - kRanges[i].lower) / (kRanges[i].upper - kRanges[i].lower))];
    }
    for (int count : bins) EXPECT_NEAR(count, N / 16, 1);
  }
}

TEST(SaltelliDesign, SkipsPoints) {
  const Eigen::MatrixXd all = SaltelliDesign(kRanges, 8, false);
  const Eigen::MatrixXd skipped = SaltelliDesign(kRanges, 4, false, 4);
  const SaltelliLayout layout{3, 8, false};
  EXPECT_EQ(skipped.row(0), all.row(static_cast<Eigen::Index>(layout.RowA(4))));
}

TEST(SaltelliDesign, RejectsBadInput) {
  EXPECT_THROW(SaltelliDesign({}, 8, false), InputError);
  EXPECT_THROW(SaltelliDesign({{"a", 1.0, 1.0}}, 8, false), InputError);
  EXPECT_THROW(SaltelliDesign({{"a", 0.0, 1.0}, {"a", 0.0, 2.0}}, 8, false), InputError);
  EXPECT_THROW(SaltelliDesign(kRanges, 0, false), InputError);
  std::vector<ParameterRange> too_many;
  for (int i = 0; i <= MaxSaltelliParameters(); ++i) too_many.push_back({"p" + std::to_string(i), 0.0, 1.0});
  EXPECT_THROW(SaltelliDesign(too_many, 1, false), InputError);
}

TEST(MorrisDesign, EachTrajectoryMovesEveryParameterOnceByTheGridStep) {
  const int r = 20, levels = 4;
  const Eigen::MatrixXd X = MorrisDesign(kRanges, r, levels, 7);
  ASSERT_EQ(X.rows(), r * 4);
  const double delta = 2.0 / 3.0;  // p/(2(p−1)) for p = 4
  EXPECT_DOUBLE_EQ(MorrisUnitStep(levels), delta);
  std::set<int> first_moved;
  for (int t = 0; t < r; ++t) {
    std::set<int> moved;
    for (int k = 0; k <= 3; ++k) {
      for (int i = 0; i < 3; ++i) {
        // On the grid {0, 1/3, 2/3, 1} of the unit interval.
        const double unit = (X(t * 4 + k, i) - kRanges[i].lower) / (kRanges[i].upper - kRanges[i].lower);
        EXPECT_NEAR(unit * 3.0, std::round(unit * 3.0), 1e-9);
        EXPECT_GE(unit, -kMapTolerance);
        EXPECT_LE(unit, 1.0 + kMapTolerance);
      }
      if (k == 3) break;
      int changed = 0;
      for (int i = 0; i < 3; ++i) {
        const double step = (X(t * 4 + k + 1, i) - X(t * 4 + k, i)) / (kRanges[i].upper - kRanges[i].lower);
        if (std::abs(step) < kMapTolerance) continue;
        ++changed;
        EXPECT_NEAR(std::abs(step), delta, kMapTolerance);
        moved.insert(i);
        if (k == 0) first_moved.insert(i);
      }
      EXPECT_EQ(changed, 1);
    }
    EXPECT_EQ(moved.size(), 3u);
  }
  EXPECT_GT(first_moved.size(), 1u);  // the order is shuffled
  EXPECT_EQ(MorrisDesign(kRanges, r, levels, 7), X);
  EXPECT_NE(MorrisDesign(kRanges, r, levels, 8), X);
}

TEST(MorrisDesign, RejectsBadInput) {
  EXPECT_THROW(MorrisDesign(kRanges, 0, 4, 1), InputError);
  EXPECT_THROW(MorrisDesign(kRanges, 4, 3, 1), InputError);
  EXPECT_THROW(MorrisDesign(kRanges, 4, 0, 1), InputError);
}

}  // namespace
}  // namespace gesweep
