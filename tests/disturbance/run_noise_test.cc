// Randomness as data (docs/disturbance.md): the noise of a run is a function of (seed, run, stream,
// index) alone, and it is standard normal white noise.
#include "engine/disturbance/run_noise.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

namespace gesweep {
namespace {

constexpr int kSamples = 1 << 20;
// Sample moments of N standard normals: mean sd 1/√N, variance sd √(2/N), correlations sd 1/√N.
// 5 sd: a fixed seed either passes or not, and a defect (a bias of 0.5 %) is > 5 sd at this N.
const double kMeanTolerance = 5.0 / std::sqrt(kSamples);
const double kVarianceTolerance = 5.0 * std::sqrt(2.0 / kSamples);
const double kCorrelationTolerance = 5.0 / std::sqrt(kSamples);

std::vector<double> Draw(const RunNoise& noise, NoiseStream stream, int n) {
  std::vector<double> v(n);
  for (int k = 0; k < n; ++k) v[k] = noise.StandardNormal(stream, k);
  return v;
}

double Correlation(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s / static_cast<double>(a.size());
}

TEST(RunNoise, SplitMixFinaliserKnownValue) {
  // splitmix64.c seeded with 0: its first output is Mix(0x9e3779b97f4a7c15) = 0xe220a8397b1dcdaf
  // (the reference implementation's published first value).
  EXPECT_EQ(SplitMix64Mix(0x9e3779b97f4a7c15ULL), 0xe220a8397b1dcdafULL);
}

TEST(RunNoise, SameSeedSameSequenceOtherRunOtherSequence) {
  const RunNoise a(42, 7), b(42, 7), c(42, 8), d(43, 7);
  EXPECT_EQ(a.key(), b.key());
  EXPECT_NE(a.key(), c.key());
  EXPECT_NE(a.key(), d.key());
  int equal_to_c = 0;
  for (int k = 0; k < 1000; ++k) {
    EXPECT_EQ(a.StandardNormal(NoiseStream::kTurbulenceW, k), b.StandardNormal(NoiseStream::kTurbulenceW, k));
    equal_to_c +=
        a.StandardNormal(NoiseStream::kTurbulenceW, k) == c.StandardNormal(NoiseStream::kTurbulenceW, k);
  }
  EXPECT_EQ(equal_to_c, 0);
}

TEST(RunNoise, IndependentOfCallOrder) {
  const RunNoise noise(2026, 123456);
  const std::vector<double> forward = Draw(noise, NoiseStream::kTurbulenceU, 5000);
  std::vector<int> order(5000);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(1));
  const RunNoise fresh(2026, 123456);
  // Another run's draws in between must not matter either.
  const RunNoise other(2026, 1);
  for (int k : order) {
    (void)other.StandardNormal(NoiseStream::kTurbulenceU, k);
    EXPECT_EQ(fresh.StandardNormal(NoiseStream::kTurbulenceU, k), forward[k]) << k;
  }
}

TEST(RunNoise, StandardNormalWhiteAndIndependentAcrossStreamsAndRuns) {
  const RunNoise run0(9, 0), run1(9, 1);
  const std::vector<double> u = Draw(run0, NoiseStream::kTurbulenceU, kSamples);
  const std::vector<double> w = Draw(run0, NoiseStream::kTurbulenceW, kSamples);
  const std::vector<double> u1 = Draw(run1, NoiseStream::kTurbulenceU, kSamples);
  const double mean = std::accumulate(u.begin(), u.end(), 0.0) / kSamples;
  EXPECT_NEAR(mean, 0.0, kMeanTolerance);
  EXPECT_NEAR(Correlation(u, u), 1.0, kVarianceTolerance);
  // Fourth moment of a normal is 3 (sd √(96/N)): the Box–Muller output is normal, not just unit variance.
  double m4 = 0;
  for (double x : u) m4 += x * x * x * x;
  EXPECT_NEAR(m4 / kSamples, 3.0, 5.0 * std::sqrt(96.0 / kSamples));
  std::vector<double> lagged(u.begin() + 1, u.end());
  lagged.push_back(u.front());
  EXPECT_NEAR(Correlation(u, lagged), 0.0, kCorrelationTolerance) << "lag-1";
  EXPECT_NEAR(Correlation(u, w), 0.0, kCorrelationTolerance) << "streams u, w";
  EXPECT_NEAR(Correlation(u, u1), 0.0, kCorrelationTolerance) << "runs 0, 1";
  const double tail =
      static_cast<double>(std::count_if(u.begin(), u.end(), [](double x) { return x > 3.0; })) / kSamples;
  // P(Z > 3) = 0.0013499; binomial sd √(p/N).
  EXPECT_NEAR(tail, 0.0013499, 5.0 * std::sqrt(0.0013499 / kSamples));
}

}  // namespace
}  // namespace gesweep
