// Designs: enumeration order, the Saltelli layout, the Sobol' points, Latin-hypercube strata and
// Morris trajectories, each against an oracle that does not come from the code under test
// (published points, nested loops, counting arguments).
#include "engine/sweep/design.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace gesweep {
namespace {

// A design value is lower + u·width with u a multiple of 1/(p−1): mapping back to the unit interval
// costs a few ulps of values below 20.
constexpr double kUnitMapTolerance = 1e-12;

DesignParameter Axis(const char* name, std::vector<double> values) {
  DesignParameter p;
  p.id = RequireParameter(name);
  p.values = std::move(values);
  return p;
}

DesignParameter Bounds(const char* name, double lower, double upper) {
  DesignParameter p;
  p.id = RequireParameter(name);
  p.lower = lower;
  p.upper = upper;
  return p;
}

TEST(GridDesign, EnumeratesTheCartesianProductLastAxisFastest) {
  DesignSpec spec;
  spec.kind = DesignKind::kGrid;
  spec.parameters = {Axis("speed_mps", {30, 40}), Axis("height_m", {1, 2, 3}), Axis("x1", {7, 8})};
  auto design = MakeDesign(spec);
  ASSERT_EQ(design->run_count(), 12);
  // Oracle: nested loops in declaration order.
  std::int64_t index = 0;
  double row[3];
  for (double u : {30.0, 40.0}) {
    for (double h : {1.0, 2.0, 3.0}) {
      for (double x : {7.0, 8.0}) {
        design->Row(index++, row);
        EXPECT_EQ(row[0], u);
        EXPECT_EQ(row[1], h);
        EXPECT_EQ(row[2], x);
      }
    }
  }
}

TEST(GridDesign, CountRunsRefusesOverflow) {
  DesignSpec spec;
  spec.kind = DesignKind::kGrid;
  std::vector<double> million(1000000);
  for (std::size_t i = 0; i < million.size(); ++i) million[i] = static_cast<double>(i);
  for (const char* name : {"x1", "x2", "x3", "x4"}) spec.parameters.push_back(Axis(name, million));
  EXPECT_EQ(CountRuns(spec), -1);  // 1e24 runs
  spec.parameters.resize(3);
  EXPECT_EQ(CountRuns(spec), 1000000LL * 1000000LL * 1000000LL);  // 1e18 < 2^62: countable, lazily
  auto design = MakeDesign(spec);
  double row[3];
  design->Row(design->run_count() - 1, row);  // the last run, without enumerating the others
  EXPECT_EQ(row[0], 999999);
  EXPECT_EQ(row[1], 999999);
  EXPECT_EQ(row[2], 999999);
}

// The first points of the 2-D Sobol' sequence (Sobol' 1967; Joe & Kuo direction numbers), as
// published e.g. in scipy.stats.qmc.Sobol(d=2, scramble=False): after the origin,
// (0.5, 0.5), (0.75, 0.25), (0.25, 0.75), (0.375, 0.375), (0.875, 0.875), (0.625, 0.125).
TEST(SobolPoint, MatchesThePublishedSequenceWithoutTheOrigin) {
  const double expected[6][2] = {{0.5, 0.5},     {0.75, 0.25},   {0.25, 0.75},
                                 {0.375, 0.375}, {0.875, 0.875}, {0.625, 0.125}};
  for (int j = 0; j < 6; ++j) {
    double point[2];
    SobolPoint(2, j, point);
    EXPECT_EQ(point[0], expected[j][0]) << "point " << j;
    EXPECT_EQ(point[1], expected[j][1]) << "point " << j;
  }
}

TEST(SobolPoint, FirstTwoToTheMPointsAreStratified) {
  // Every dyadic interval [k/2^m, (k+1)/2^m) of each coordinate holds exactly one of the points
  // 0..2^m−1 of a (0,1)-sequence in one dimension; with the origin skipped, points 1..2^m hit each
  // interval once too except [0, 2^-m) traded for the point 2^m. Check the 1-D projections.
  constexpr int kM = 8;
  constexpr int kPoints = 1 << kM;
  for (int d = 0; d < 6; ++d) {
    std::vector<int> hits(kPoints, 0);
    for (int j = 0; j < kPoints - 1; ++j) {
      double point[6];
      SobolPoint(6, j, point);
      ++hits[static_cast<std::size_t>(point[d] * kPoints)];
    }
    // Points 1..2^m−1 plus the skipped origin fill every interval exactly once.
    ++hits[0];
    for (int k = 0; k < kPoints; ++k)
      EXPECT_EQ(hits[static_cast<std::size_t>(k)], 1) << "dimension " << d << " cell " << k;
  }
}

TEST(SaltelliDesign, RowsFollowSalibsBlockLayout) {
  for (bool second_order : {false, true}) {
    DesignSpec spec;
    spec.kind = DesignKind::kSobol;
    spec.base_samples = 5;
    spec.second_order = second_order;
    spec.parameters = {Bounds("x1", -3, 3), Bounds("x2", 0, 1), Bounds("x3", 10, 20)};
    const int D = 3;
    auto design = MakeDesign(spec);
    const std::int64_t block = second_order ? 2 * D + 2 : D + 2;
    ASSERT_EQ(design->run_count(), 5 * block);
    for (std::int64_t j = 0; j < 5; ++j) {
      // Oracle: A and B straight from the Sobol' point, mapped by hand.
      double point[2 * D];
      SobolPoint(2 * D, j, point);
      const double lower[D] = {-3, 0, 10}, width[D] = {6, 1, 10};
      double a[D], b[D];
      for (int d = 0; d < D; ++d) {
        a[d] = lower[d] + point[d] * width[d];
        b[d] = lower[d] + point[D + d] * width[d];
      }
      double row[D];
      design->Row(j * block, row);
      for (int d = 0; d < D; ++d) EXPECT_EQ(row[d], a[d]);
      for (int i = 0; i < D; ++i) {
        design->Row(j * block + 1 + i, row);  // AB^(i): A with column i from B
        for (int d = 0; d < D; ++d) EXPECT_EQ(row[d], d == i ? b[d] : a[d]);
        if (second_order) {
          design->Row(j * block + 1 + D + i, row);  // BA^(i): B with column i from A
          for (int d = 0; d < D; ++d) EXPECT_EQ(row[d], d == i ? a[d] : b[d]);
        }
      }
      design->Row(j * block + block - 1, row);
      for (int d = 0; d < D; ++d) EXPECT_EQ(row[d], b[d]);
    }
  }
}

TEST(LatinHypercube, EveryStratumOfEveryDimensionHoldsExactlyOnePoint) {
  for (std::int64_t n : {1, 2, 7, 64, 1000, 4099}) {
    DesignSpec spec;
    spec.kind = DesignKind::kLhs;
    spec.samples = n;
    spec.seed = 12345;
    spec.parameters = {Bounds("x1", 0, 1), Bounds("x2", -2, 2), Bounds("x3", 5, 6)};
    auto design = MakeDesign(spec);
    std::vector<std::vector<int>> hits(3, std::vector<int>(static_cast<std::size_t>(n), 0));
    for (std::int64_t i = 0; i < n; ++i) {
      double row[3];
      design->Row(i, row);
      const double unit[3] = {row[0], (row[1] + 2) / 4, row[2] - 5};
      for (int d = 0; d < 3; ++d) {
        ASSERT_GE(unit[d], 0.0);
        ASSERT_LT(unit[d], 1.0);
        ++hits[static_cast<std::size_t>(d)]
              [static_cast<std::size_t>(std::floor(unit[d] * static_cast<double>(n)))];
      }
    }
    for (int d = 0; d < 3; ++d) {
      for (std::int64_t k = 0; k < n; ++k) {
        ASSERT_EQ(hits[static_cast<std::size_t>(d)][static_cast<std::size_t>(k)], 1)
            << "n " << n << " dim " << d;
      }
    }
  }
}

TEST(LatinHypercube, SeedChangesTheDesignAndTheSameSeedRepeatsIt) {
  auto row_of = [](std::uint64_t seed, std::int64_t i) {
    DesignSpec spec;
    spec.kind = DesignKind::kLhs;
    spec.samples = 100;
    spec.seed = seed;
    spec.parameters = {Bounds("x1", 0, 1), Bounds("x2", 0, 1)};
    double row[2];
    MakeDesign(spec)->Row(i, row);
    return std::pair<double, double>(row[0], row[1]);
  };
  EXPECT_EQ(row_of(1, 17), row_of(1, 17));
  int differ = 0;
  for (int i = 0; i < 100; ++i) differ += row_of(1, i) != row_of(2, i);
  EXPECT_GT(differ, 90);
  // The two dimensions are permuted independently: not the same stratum order.
  int same = 0;
  for (int i = 0; i < 100; ++i) same += LatinStratum(1, 0, 100, i) == LatinStratum(1, 1, 100, i);
  EXPECT_LT(same, 10);
}

TEST(MorrisDesign, TrajectoriesChangeOneFactorByDeltaPerStepOnTheLevelGrid) {
  DesignSpec spec;
  spec.kind = DesignKind::kMorris;
  spec.trajectories = 50;
  spec.levels = 4;
  spec.seed = 7;
  spec.parameters = {Bounds("x1", 0, 1), Bounds("x2", 10, 20), Bounds("x3", -1, 1), Bounds("x4", 0, 3)};
  const int D = 4;
  const double lower[D] = {0, 10, -1, 0}, width[D] = {1, 10, 2, 3};
  const double delta = 4.0 / (2.0 * 3.0);  // p/(2(p−1)), Morris (1991)
  auto design = MakeDesign(spec);
  ASSERT_EQ(design->run_count(), 50 * (D + 1));
  std::map<int, int> changes;
  std::set<int> first_moved;
  int upward = 0, downward = 0;
  for (std::int64_t t = 0; t < 50; ++t) {
    std::set<int> changed;
    double previous[D];
    for (int s = 0; s <= D; ++s) {
      double row[D];
      design->Row(t * (D + 1) + s, row);
      for (int d = 0; d < D; ++d) {
        const double unit = (row[d] - lower[d]) / width[d];
        const double level = unit * 3.0;  // levels 0, 1/3, 2/3, 1
        EXPECT_NEAR(level, std::round(level), kUnitMapTolerance) << "off the level grid";
      }
      if (s > 0) {
        int moved = 0;
        for (int d = 0; d < D; ++d) {
          if (row[d] != previous[d]) {
            ++moved;
            changed.insert(d);
            if (s == 1) first_moved.insert(d);
            (row[d] > previous[d] ? upward : downward) += 1;
            EXPECT_NEAR(std::abs(row[d] - previous[d]) / width[d], delta, kUnitMapTolerance);
          }
        }
        EXPECT_EQ(moved, 1) << "trajectory " << t << " step " << s;
      }
      std::copy(row, row + D, previous);
    }
    EXPECT_EQ(changed.size(), static_cast<std::size_t>(D)) << "each factor moves once per trajectory";
    for (int d : changed) ++changes[d];
  }
  // Random order and direction (Morris 1991): over 50 trajectories every factor comes first at least
  // once and both directions occur (a fair draw misses a first factor with probability 4·(3/4)^50 ≈ 2e-6;
  // the draws are fixed by the seed, so the test is deterministic).
  EXPECT_EQ(first_moved.size(), static_cast<std::size_t>(D));
  EXPECT_GT(upward, 0);
  EXPECT_GT(downward, 0);
}

TEST(MorrisDesign, IsReproducibleFromItsSeed) {
  auto first_rows = [](std::uint64_t seed) {
    DesignSpec spec;
    spec.kind = DesignKind::kMorris;
    spec.trajectories = 10;
    spec.levels = 6;
    spec.seed = seed;
    spec.parameters = {Bounds("x1", 0, 1), Bounds("x2", 0, 1)};
    auto design = MakeDesign(spec);
    std::vector<double> values;
    for (std::int64_t i = 0; i < design->run_count(); ++i) {
      double row[2];
      design->Row(i, row);
      values.insert(values.end(), row, row + 2);
    }
    return values;
  };
  EXPECT_EQ(first_rows(3), first_rows(3));
  EXPECT_NE(first_rows(3), first_rows(4));
}

TEST(MapUnit, LogUniformSpacesGeometrically) {
  DesignParameter p = Bounds("x1", 1, 100);
  p.distribution = Distribution::kLogUniform;
  EXPECT_DOUBLE_EQ(MapUnit(p, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(MapUnit(p, 0.5), 10.0);
  p.distribution = Distribution::kUniform;
  EXPECT_DOUBLE_EQ(MapUnit(p, 0.5), 50.5);
}

// --- monte_carlo ------------------------------------------------------------------------------

// The analytic CDFs of the test, from std::erfc (not from the Boost.Math the design uses).
double Phi(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

// Kolmogorov–Smirnov: the design is seeded, so a sample either passes or not, every time; the
// critical value is the asymptotic one at significance 0.001, c = sqrt(-ln(0.0005)/2) = 1.9495, over
// sqrt(n): a correct sampler fails it with probability 0.001 for a given seed, a wrong mapping (a
// shifted mean by 0.05 sigma at n = 20000, a wrong sigma by 3 %) fails it surely.
constexpr double kKolmogorovCritical001 = 1.9495;
constexpr std::int64_t kSamples = 20000;

template <typename Cdf>
double KolmogorovStatistic(std::vector<double> sample, Cdf cdf) {
  std::sort(sample.begin(), sample.end());
  const auto n = static_cast<double>(sample.size());
  double d = 0;
  for (std::size_t i = 0; i < sample.size(); ++i) {
    const double f = cdf(sample[i]);
    d = std::max({d, f - static_cast<double>(i) / n, static_cast<double>(i + 1) / n - f});
  }
  return d;
}

std::vector<double> Column(const Design& design, int column) {
  std::vector<double> row(static_cast<std::size_t>(design.column_count())), values;
  for (std::int64_t i = 0; i < design.run_count(); ++i) {
    design.Row(i, row.data());
    values.push_back(row[static_cast<std::size_t>(column)]);
  }
  return values;
}

DesignSpec MonteCarloSpec() {
  DesignSpec spec;
  spec.kind = DesignKind::kMonteCarlo;
  spec.samples = kSamples;
  spec.seed = 2024;
  DesignParameter normal;
  normal.id = RequireParameter("speed_mps");
  normal.distribution = Distribution::kNormal;
  normal.mean = 32;
  normal.sigma = 0.8;
  DesignParameter truncated;
  truncated.id = RequireParameter("height_m");
  truncated.distribution = Distribution::kTruncatedNormal;
  truncated.mean = 2;
  truncated.sigma = 1;
  truncated.truncate_lower = 2.5;  // above the mean: the mirrored branch
  truncated.truncate_upper = 4;
  DesignParameter lognormal;
  lognormal.id = RequireParameter("mass_kg");
  lognormal.distribution = Distribution::kLogNormal;
  lognormal.mean = std::log(30.0);
  lognormal.sigma = 0.1;
  DesignParameter uniform;
  uniform.id = RequireParameter("x1");
  uniform.distribution = Distribution::kUniform;
  uniform.lower = -1;
  uniform.upper = 3;
  DesignParameter discrete;
  discrete.id = RequireParameter("x2");
  discrete.distribution = Distribution::kDiscrete;
  discrete.values = {0, 1, 5};
  discrete.weights = {1, 2, 7};
  DesignParameter lower_truncated;
  lower_truncated.id = RequireParameter("x3");
  lower_truncated.distribution = Distribution::kTruncatedNormal;
  lower_truncated.mean = 0;
  lower_truncated.sigma = 2;
  lower_truncated.truncate_lower = -1;
  lower_truncated.truncate_upper = 5;
  spec.parameters = {normal, truncated, lognormal, uniform, discrete, lower_truncated};
  return spec;
}

TEST(MonteCarloDesign, EachColumnFollowsItsDistributionByKolmogorovSmirnov) {
  const auto design = MakeDesign(MonteCarloSpec());
  ASSERT_EQ(design->run_count(), kSamples);
  const double critical = kKolmogorovCritical001 / std::sqrt(static_cast<double>(kSamples));
  EXPECT_LT(KolmogorovStatistic(Column(*design, 0), [](double x) { return Phi((x - 32) / 0.8); }), critical);
  const double mass = Phi(2.0) - Phi(0.5);
  EXPECT_LT(KolmogorovStatistic(Column(*design, 1), [&](double x) { return (Phi(x - 2) - Phi(0.5)) / mass; }),
            critical);
  EXPECT_LT(KolmogorovStatistic(Column(*design, 2),
                                [](double x) { return Phi((std::log(x) - std::log(30.0)) / 0.1); }),
            critical);
  EXPECT_LT(KolmogorovStatistic(Column(*design, 3), [](double x) { return (x + 1) / 4; }), critical);
  const double lower_mass = Phi(2.5) - Phi(-0.5);
  EXPECT_LT(KolmogorovStatistic(Column(*design, 5),
                                [&](double x) { return (Phi(x / 2) - Phi(-0.5)) / lower_mass; }),
            critical);
  // Every truncated draw inside its interval.
  for (double x : Column(*design, 1)) ASSERT_TRUE(x >= 2.5 && x <= 4) << x;
  for (double x : Column(*design, 5)) ASSERT_TRUE(x >= -1 && x <= 5) << x;
}

TEST(MonteCarloDesign, MomentsMatchTheAnalyticOnesWithinFiveStandardErrors) {
  const auto design = MakeDesign(MonteCarloSpec());
  const auto n = static_cast<double>(kSamples);
  // Five standard errors: a correct sampler is outside with probability 6e-7.
  constexpr double kStandardErrors = 5;
  const std::vector<double> normal = Column(*design, 0);
  double mean = 0;
  for (double x : normal) mean += x / n;
  double variance = 0;
  for (double x : normal) variance += (x - mean) * (x - mean) / (n - 1);
  EXPECT_NEAR(mean, 32, kStandardErrors * 0.8 / std::sqrt(n));
  // The sample variance's standard error is sigma² sqrt(2/(n − 1)) for a normal sample.
  EXPECT_NEAR(variance, 0.64, kStandardErrors * 0.64 * std::sqrt(2 / (n - 1)));
  // Lognormal: E = exp(mu + sigma²/2).
  double lognormal_mean = 0;
  for (double x : Column(*design, 2)) lognormal_mean += x / n;
  const double expected = 30 * std::exp(0.005);
  const double sd = expected * std::sqrt(std::exp(0.01) - 1);
  EXPECT_NEAR(lognormal_mean, expected, kStandardErrors * sd / std::sqrt(n));
}

TEST(MonteCarloDesign, DiscreteValuesComeInProportionToTheirWeights) {
  const auto design = MakeDesign(MonteCarloSpec());
  std::map<double, double> counts;
  for (double x : Column(*design, 4)) counts[x] += 1;
  ASSERT_EQ(counts.size(), 3u);
  const auto n = static_cast<double>(kSamples);
  constexpr double kStandardErrors = 5;  // binomial standard errors; outside with probability 6e-7
  const std::map<double, double> expected = {{0, 0.1}, {1, 0.2}, {5, 0.7}};
  for (const auto& [value, p] : expected) {
    EXPECT_NEAR(counts[value] / n, p, kStandardErrors * std::sqrt(p * (1 - p) / n)) << value;
  }
}

TEST(MonteCarloDesign, RowDependsOnSeedIndexAndNameOnlyNotOnColumnOrOtherParameters) {
  DesignSpec spec = MonteCarloSpec();
  const auto design = MakeDesign(spec);
  std::vector<double> full(spec.parameters.size());
  design->Row(1234, full.data());
  // The same parameter alone in a design of one column, at the same index and seed: the same value.
  DesignSpec alone = spec;
  alone.parameters = {spec.parameters[2]};
  double value = 0;
  MakeDesign(alone)->Row(1234, &value);
  EXPECT_EQ(value, full[2]);
  // Rows computed out of order equal rows computed in order.
  std::vector<double> again(spec.parameters.size());
  for (std::int64_t i = kSamples - 1; i >= 0; i -= 997) {
    design->Row(i, again.data());
    std::vector<double> fresh(spec.parameters.size());
    MakeDesign(spec)->Row(i, fresh.data());
    EXPECT_EQ(again, fresh);
  }
  // Another seed, other values.
  spec.seed = 2025;
  std::vector<double> other(spec.parameters.size());
  MakeDesign(spec)->Row(1234, other.data());
  EXPECT_NE(other[0], full[0]);
}

TEST(MonteCarloDesign, UnitCoordinatesStayStrictlyInsideTheUnitInterval) {
  // The extremes are the reach the study checks: Phi^-1(2^-53) = -8.2095 (scipy.stats.norm.ppf), so a
  // normal's draws stay within mean ± 8.21 sigma, symmetrically.
  constexpr double kReach = 8.21;
  DesignParameter normal;
  normal.id = RequireParameter("speed_mps");
  normal.distribution = Distribution::kNormal;
  normal.mean = 0;
  normal.sigma = 1;
  EXPECT_GT(MonteCarloValue(normal, kMonteCarloUnitLow), -kReach);
  EXPECT_LT(MonteCarloValue(normal, kMonteCarloUnitLow), -8.2);
  EXPECT_LT(MonteCarloValue(normal, kMonteCarloUnitHigh), kReach);
  EXPECT_EQ(MonteCarloValue(normal, kMonteCarloUnitHigh), -MonteCarloValue(normal, kMonteCarloUnitLow));
  for (std::int64_t i = 0; i < 1000; ++i) {
    const double u = MonteCarloUnit(7, i, normal.id);
    ASSERT_TRUE(u >= kMonteCarloUnitLow && u <= kMonteCarloUnitHigh) << u;
  }
}

// MonteCarloValueAtNormal (a subset simulation's random parameters): the value whose CDF is Φ(z).
// Oracles: the normal kinds in closed form; the others at Φ(z) = erfc(−z/√2)/2 (std::erfc, not the
// engine's Boost.Math), through the distributions' own closed-form quantiles.
TEST(MonteCarloValueAtNormal, IsTheValueWhoseCumulativeProbabilityIsPhiOfZ) {
  const DesignSpec spec = MonteCarloSpec();
  const DesignParameter& normal = spec.parameters[0];     // normal(32, 0.8)
  const DesignParameter& lognormal = spec.parameters[2];  // lognormal(log 30, 0.1)
  const DesignParameter& uniform = spec.parameters[3];    // uniform(-1, 3)
  const DesignParameter& discrete = spec.parameters[4];   // {0, 1, 5} weights {1, 2, 7}
  const auto phi = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  for (const double z : {-12.0, -5.2, -1.0, 0.0, 0.3, 2.0, 5.2, 12.0}) {
    // The normal kinds take z itself, however far into the tail: exact.
    EXPECT_EQ(MonteCarloValueAtNormal(normal, z), 32 + 0.8 * z);
    EXPECT_EQ(MonteCarloValueAtNormal(lognormal, z), std::exp(std::log(30.0) + 0.1 * z));
    const double u = std::clamp(phi(z), kMonteCarloUnitLow, kMonteCarloUnitHigh);
    EXPECT_NEAR(MonteCarloValueAtNormal(uniform, z), -1 + 4 * u, kUnitMapTolerance) << z;
    const double expected_discrete = u * 10 < 1 ? 0 : (u * 10 < 3 ? 1 : 5);
    EXPECT_EQ(MonteCarloValueAtNormal(discrete, z), expected_discrete) << z;
  }
  // Beyond the monte_carlo design's extreme unit coordinates, the bounded kinds stop at its reach.
  EXPECT_EQ(MonteCarloValueAtNormal(uniform, 40.0), MonteCarloValue(uniform, kMonteCarloUnitHigh));
  EXPECT_EQ(MonteCarloValueAtNormal(uniform, -40.0), MonteCarloValue(uniform, kMonteCarloUnitLow));
  const DesignParameter& truncated = spec.parameters[1];  // normal(2, 1) on [2.5, 4]
  EXPECT_GE(MonteCarloValueAtNormal(truncated, -40.0), 2.5);
  EXPECT_LE(MonteCarloValueAtNormal(truncated, 40.0), 4.0);
}

}  // namespace
}  // namespace gesweep
