#include "engine/sweep/design.h"

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <boost/random/sobol.hpp>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "engine/common/errors.h"
#include "engine/estimators/sensitivity_common.h"
#include "engine/sweep/hashing.h"

namespace gesweep {
namespace {

// Stream tags keep the random streams of different purposes independent for one seed.
constexpr std::uint64_t kLatinPermutationTag = 0x4c48535f7065726dULL;  // "LHS_perm"
constexpr std::uint64_t kLatinJitterTag = 0x4c48535f6a697474ULL;       // "LHS_jitt"
constexpr std::uint64_t kMorrisTag = 0x4d4f52524953ULL;                // "MORRIS"
constexpr std::uint64_t kMonteCarloTag = 0x4d4f4e54455f4341ULL;        // "MONTE_CA"
constexpr int kFeistelRounds = 4;  // four rounds make a keyed Feistel network a good permutation
constexpr std::int64_t kMaximumRuns = std::int64_t{1} << 62;
static_assert(2 * kMaximumSobolParameters <=
                  static_cast<int>(boost::random::detail::qrng_tables::sobol::max_dimension),
              "a sobol design of kMaximumSobolParameters needs 2D dimensions of Boost's Sobol' tables");
// Largest double below 1: a unit coordinate never reaches the upper bound by rounding.
constexpr double kBelowOne = 1.0 - 0x1.0p-53;

double Clamp01(double u) { return u < kBelowOne ? u : kBelowOne; }

class SingleDesign final : public Design {
 public:
  explicit SingleDesign(DesignSpec spec) : Design(std::move(spec)) {}
  std::int64_t run_count() const override { return 1; }
  void Row(std::int64_t, double*) const override {}
};

class GridDesign final : public Design {
 public:
  explicit GridDesign(DesignSpec spec) : Design(std::move(spec)), count_(CountRuns(spec_)) {}
  std::int64_t run_count() const override { return count_; }
  void Row(std::int64_t index, double* values) const override {
    GESWEEP_DEMAND(index >= 0 && index < count_);
    for (int d = column_count() - 1; d >= 0; --d) {
      const auto& axis = spec_.parameters[static_cast<std::size_t>(d)].values;
      const auto size = static_cast<std::int64_t>(axis.size());
      values[d] = axis[static_cast<std::size_t>(index % size)];
      index /= size;
    }
  }

 private:
  std::int64_t count_;
};

class ListDesign final : public Design {
 public:
  explicit ListDesign(DesignSpec spec) : Design(std::move(spec)) {
    GESWEEP_DEMAND(spec_.list_values.size() ==
                   static_cast<std::size_t>(spec_.list_rows) * static_cast<std::size_t>(column_count()));
  }
  std::int64_t run_count() const override { return spec_.list_rows; }
  void Row(std::int64_t index, double* values) const override {
    GESWEEP_DEMAND(index >= 0 && index < spec_.list_rows);
    const std::size_t begin = static_cast<std::size_t>(index) * static_cast<std::size_t>(column_count());
    for (int d = 0; d < column_count(); ++d)
      values[d] = spec_.list_values[begin + static_cast<std::size_t>(d)];
  }
};

class LatinHypercubeDesign final : public Design {
 public:
  explicit LatinHypercubeDesign(DesignSpec spec) : Design(std::move(spec)) {}
  std::int64_t run_count() const override { return spec_.samples; }
  void Row(std::int64_t index, double* values) const override {
    GESWEEP_DEMAND(index >= 0 && index < spec_.samples);
    const std::int64_t n = spec_.samples;
    for (int d = 0; d < column_count(); ++d) {
      const std::int64_t stratum = LatinStratum(spec_.seed, d, n, index);
      const double jitter = UnitInterval(HashWords(
          spec_.seed ^ kLatinJitterTag, static_cast<std::uint64_t>(d), static_cast<std::uint64_t>(index)));
      const double u = Clamp01((static_cast<double>(stratum) + jitter) / static_cast<double>(n));
      values[d] = MapUnit(spec_.parameters[static_cast<std::size_t>(d)], u);
    }
  }
};

class SaltelliDesign final : public Design {
 public:
  explicit SaltelliDesign(DesignSpec spec)
      : Design(std::move(spec)), block_rows_(SaltelliBlockRows(column_count(), spec_.second_order)) {}
  std::int64_t run_count() const override { return spec_.base_samples * block_rows_; }
  void Row(std::int64_t index, double* values) const override {
    GESWEEP_DEMAND(index >= 0 && index < run_count());
    const int D = column_count();
    const std::int64_t j = index / block_rows_;
    const std::int64_t k = index % block_rows_;
    std::vector<double> point(static_cast<std::size_t>(2 * D));
    SobolPoint(2 * D, j, point.data());
    const double* a = point.data();
    const double* b = point.data() + D;
    for (int d = 0; d < D; ++d) {
      const double u = SaltelliTakesB(D, spec_.second_order, k, d) ? b[d] : a[d];
      values[d] = MapUnit(spec_.parameters[static_cast<std::size_t>(d)], u);
    }
  }

 private:
  std::int64_t block_rows_;
};

class MorrisDesign final : public Design {
 public:
  explicit MorrisDesign(DesignSpec spec) : Design(std::move(spec)) {}
  std::int64_t run_count() const override { return spec_.trajectories * (column_count() + 1); }
  void Row(std::int64_t index, double* values) const override {
    GESWEEP_DEMAND(index >= 0 && index < run_count());
    const int D = column_count();
    const std::int64_t trajectory = index / (D + 1);
    const int step = static_cast<int>(index % (D + 1));
    const int p = spec_.levels;
    const double delta = p / (2.0 * (p - 1));
    // The draws of one trajectory, always in the same order: base levels, directions, order.
    SplitMixStream stream(HashWords(spec_.seed, kMorrisTag, static_cast<std::uint64_t>(trajectory)));
    std::vector<double> start(static_cast<std::size_t>(D)), other(static_cast<std::size_t>(D));
    for (int d = 0; d < D; ++d) {
      const double low = static_cast<double>(stream.Below(static_cast<std::uint64_t>(p / 2))) / (p - 1);
      const bool upward = stream.Below(2) == 1;
      start[static_cast<std::size_t>(d)] = upward ? low : low + delta;
      other[static_cast<std::size_t>(d)] = upward ? low + delta : low;
    }
    std::vector<int> order(static_cast<std::size_t>(D));
    std::iota(order.begin(), order.end(), 0);
    for (int i = D - 1; i > 0; --i) {
      const auto j = static_cast<int>(stream.Below(static_cast<std::uint64_t>(i) + 1));
      std::swap(order[static_cast<std::size_t>(i)], order[static_cast<std::size_t>(j)]);
    }
    std::vector<double> x = start;
    for (int s = 0; s < step; ++s) {
      const auto factor = static_cast<std::size_t>(order[static_cast<std::size_t>(s)]);
      x[factor] = other[factor];
    }
    for (int d = 0; d < D; ++d) {
      values[d] = MapUnit(spec_.parameters[static_cast<std::size_t>(d)], x[static_cast<std::size_t>(d)]);
    }
  }
};

class MonteCarloDesign final : public Design {
 public:
  explicit MonteCarloDesign(DesignSpec spec) : Design(std::move(spec)) {}
  std::int64_t run_count() const override { return spec_.samples; }
  void Row(std::int64_t index, double* values) const override {
    GESWEEP_DEMAND(index >= 0 && index < spec_.samples);
    for (int d = 0; d < column_count(); ++d) {
      const DesignParameter& parameter = spec_.parameters[static_cast<std::size_t>(d)];
      values[d] = MonteCarloValue(parameter, MonteCarloUnit(spec_.seed, index, parameter.id));
    }
  }
};

// The standard normal's quantile and distribution function (Boost.Math).
double StandardNormalQuantile(double p) { return boost::math::quantile(boost::math::normal(), p); }
double StandardNormalCdf(double z) { return boost::math::cdf(boost::math::normal(), z); }

// A keyed Feistel network on `bits` (even) bits: a bijection of [0, 2^bits).
std::uint64_t Feistel(std::uint64_t x, int bits, std::uint64_t key) {
  const int half = bits / 2;
  const std::uint64_t mask = (std::uint64_t{1} << half) - 1;
  std::uint64_t left = x >> half, right = x & mask;
  for (int round = 0; round < kFeistelRounds; ++round) {
    const std::uint64_t f = HashWords(key, static_cast<std::uint64_t>(round), right) & mask;
    const std::uint64_t next_right = left ^ f;
    left = right;
    right = next_right;
  }
  return (left << half) | right;
}

}  // namespace

std::int64_t CountRuns(const DesignSpec& spec) {
  auto multiply = [](std::int64_t a, std::int64_t b) -> std::int64_t {
    if (a < 0 || b < 0) return -1;
    if (b != 0 && a > kMaximumRuns / b) return -1;
    return a * b;
  };
  switch (spec.kind) {
    case DesignKind::kSingle:
      return 1;
    case DesignKind::kGrid: {
      std::int64_t count = 1;
      for (const auto& p : spec.parameters)
        count = multiply(count, static_cast<std::int64_t>(p.values.size()));
      return count;
    }
    case DesignKind::kList:
      return spec.list_rows;
    case DesignKind::kLhs:
    case DesignKind::kMonteCarlo:
      return spec.samples;
    case DesignKind::kSobol:
      return multiply(spec.base_samples,
                      SaltelliBlockRows(static_cast<int>(spec.parameters.size()), spec.second_order));
    case DesignKind::kMorris:
      return multiply(spec.trajectories, static_cast<std::int64_t>(spec.parameters.size()) + 1);
  }
  return -1;
}

void SobolPoint(int dimension, std::int64_t j, double* coordinates) {
  GESWEEP_DEMAND(dimension >= 1 && j >= 0);
  boost::random::sobol engine(static_cast<std::size_t>(dimension));
  engine.seed(static_cast<std::uint64_t>(j));
  for (int d = 0; d < dimension; ++d) {
    // The engine's 64-bit integers are the binary fractions of the point: exact in a double
    // for the first 2^52 points.
    coordinates[d] = static_cast<double>(engine()) * 0x1.0p-64;
  }
}

double MapUnit(const DesignParameter& parameter, double u) {
  return ValueAtUnit(parameter.lower, parameter.upper, parameter.distribution == Distribution::kLogUniform,
                     u);
}

double MonteCarloUnit(std::uint64_t seed, std::int64_t index, ParameterId id) {
  GESWEEP_DEMAND(index >= 0);
  const std::uint64_t run_key = HashWords(seed ^ kMonteCarloTag, static_cast<std::uint64_t>(index));
  // A renamed parameter's older name (identity_name): a rename changes no draw.
  const std::uint64_t bits =
      HashWords(run_key, Fnv1a64(ParameterCatalog()[static_cast<std::size_t>(id)].identity_name));
  return (static_cast<double>(bits >> 12) + 0.5) * 0x1.0p-52;
}

double MonteCarloValue(const DesignParameter& parameter, double u) {
  GESWEEP_DEMAND(u > 0 && u < 1);
  switch (parameter.distribution) {
    case Distribution::kUniform:
    case Distribution::kLogUniform:
      return MapUnit(parameter, u);
    case Distribution::kNormal:
      return parameter.mean + parameter.sigma * StandardNormalQuantile(u);
    case Distribution::kLogNormal:
      return std::exp(parameter.mean + parameter.sigma * StandardNormalQuantile(u));
    case Distribution::kTruncatedNormal: {
      // Inverse CDF on [a, b] in standard units. An interval above the mean is drawn as the mirror
      // of its reflection, so Φ is always evaluated where it is small and keeps its relative precision.
      double a = (parameter.truncate_lower - parameter.mean) / parameter.sigma;
      double b = (parameter.truncate_upper - parameter.mean) / parameter.sigma;
      const bool mirrored = a > 0;
      if (mirrored) {
        std::swap(a, b);
        a = -a;
        b = -b;
        u = 1.0 - u;  // exact: u is an odd multiple of 2⁻⁵³ in (0, 1)
      }
      const double fa = StandardNormalCdf(a), fb = StandardNormalCdf(b);
      double z = StandardNormalQuantile(fa + u * (fb - fa));
      z = std::min(std::max(z, a), b);
      if (mirrored) z = -z;
      const double x = parameter.mean + parameter.sigma * z;
      return std::min(std::max(x, parameter.truncate_lower), parameter.truncate_upper);
    }
    case Distribution::kDiscrete: {
      GESWEEP_DEMAND(!parameter.values.empty() && parameter.weights.size() == parameter.values.size());
      double total = 0;
      for (double w : parameter.weights) total += w;
      const double target = u * total;
      double cumulative = 0;
      for (std::size_t k = 0; k < parameter.values.size(); ++k) {
        cumulative += parameter.weights[k];
        if (target < cumulative) return parameter.values[k];
      }
      return parameter.values.back();
    }
  }
  GESWEEP_UNREACHABLE();
}

double MonteCarloValueAtNormal(const DesignParameter& parameter, double z) {
  GESWEEP_DEMAND(std::isfinite(z));
  switch (parameter.distribution) {
    case Distribution::kNormal:
      return parameter.mean + parameter.sigma * z;
    case Distribution::kLogNormal:
      return std::exp(parameter.mean + parameter.sigma * z);
    default:
      return MonteCarloValue(parameter,
                             std::clamp(StandardNormalCdf(z), kMonteCarloUnitLow, kMonteCarloUnitHigh));
  }
}

double TruncatedNormalMass(const DesignParameter& parameter) {
  double a = (parameter.truncate_lower - parameter.mean) / parameter.sigma;
  double b = (parameter.truncate_upper - parameter.mean) / parameter.sigma;
  if (a > 0) {
    std::swap(a, b);
    a = -a;
    b = -b;
  }
  return StandardNormalCdf(b) - StandardNormalCdf(a);
}

std::string DescribeDistribution(const DesignParameter& parameter) {
  std::ostringstream text;
  text.precision(17);
  text << ToString(parameter.distribution);
  switch (parameter.distribution) {
    case Distribution::kUniform:
    case Distribution::kLogUniform:
      text << "(lower=" << parameter.lower << ", upper=" << parameter.upper << ")";
      break;
    case Distribution::kNormal:
      text << "(mean=" << parameter.mean << ", sigma=" << parameter.sigma << ")";
      break;
    case Distribution::kLogNormal:
      text << "(mean of log=" << parameter.mean << ", sigma of log=" << parameter.sigma << ")";
      break;
    case Distribution::kTruncatedNormal:
      text << "(mean=" << parameter.mean << ", sigma=" << parameter.sigma
           << ", lower=" << parameter.truncate_lower << ", upper=" << parameter.truncate_upper << ")";
      break;
    case Distribution::kDiscrete:
      text << "(";
      for (std::size_t k = 0; k < parameter.values.size(); ++k) {
        text << (k ? ", " : "") << FormatParameterValue(parameter.id, parameter.values[k]) << ":"
             << parameter.weights[k];
      }
      text << ")";
      break;
  }
  return text.str();
}

std::int64_t LatinStratum(std::uint64_t seed, int dimension, std::int64_t n, std::int64_t i) {
  GESWEEP_DEMAND(n >= 1 && i >= 0 && i < n);
  if (n == 1) return 0;
  int bits = 2;
  while ((std::uint64_t{1} << bits) < static_cast<std::uint64_t>(n)) bits += 2;
  const std::uint64_t key = HashWords(seed, kLatinPermutationTag, static_cast<std::uint64_t>(dimension));
  // Cycle-walking: apply the permutation of [0, 2^bits) until the value falls in [0, n); this
  // restricts it to a permutation of [0, n) (Black & Rogaway 2002).
  std::uint64_t x = static_cast<std::uint64_t>(i);
  do {
    x = Feistel(x, bits, key);
  } while (x >= static_cast<std::uint64_t>(n));
  return static_cast<std::int64_t>(x);
}

std::unique_ptr<Design> MakeDesign(DesignSpec spec) {
  GESWEEP_DEMAND(CountRuns(spec) >= 1);
  switch (spec.kind) {
    case DesignKind::kSingle:
      return std::make_unique<SingleDesign>(std::move(spec));
    case DesignKind::kGrid:
      return std::make_unique<GridDesign>(std::move(spec));
    case DesignKind::kList:
      return std::make_unique<ListDesign>(std::move(spec));
    case DesignKind::kLhs:
      return std::make_unique<LatinHypercubeDesign>(std::move(spec));
    case DesignKind::kSobol:
      return std::make_unique<SaltelliDesign>(std::move(spec));
    case DesignKind::kMorris:
      return std::make_unique<MorrisDesign>(std::move(spec));
    case DesignKind::kMonteCarlo:
      return std::make_unique<MonteCarloDesign>(std::move(spec));
  }
  GESWEEP_UNREACHABLE();
}

}  // namespace gesweep
