#include "engine/analysis/sensitivity_design.h"

#include <boost/random/mersenne_twister.hpp>
#include <boost/random/sobol.hpp>
#include <boost/random/uniform_int_distribution.hpp>
#include <cmath>
#include <set>
#include <utility>

#include "engine/common/errors.h"

namespace gesweep {

int MaxSaltelliParameters() {
  return static_cast<int>(boost::random::detail::qrng_tables::sobol::max_dimension / 2);
}

void ValidateRanges(const std::vector<ParameterRange>& ranges, const std::string& source) {
  if (ranges.empty()) throw InputError(source, "parameters", "", "expected at least one sampled parameter");
  std::set<std::string> names;
  for (const auto& range : ranges) {
    if (range.name.empty()) throw InputError(source, "parameters", "''", "expected a non-empty parameter name");
    if (!names.insert(range.name).second) {
      throw InputError(source, range.name, "", "parameter listed twice; expected distinct names");
    }
    if (!std::isfinite(range.lower) || !std::isfinite(range.upper) || !(range.lower < range.upper)) {
      throw InputError(source, range.name, "[" + ShortNumber(range.lower) + ", " + ShortNumber(range.upper) + "]",
                       "expected finite bounds with lower < upper");
    }
    if (range.log_uniform && !(range.lower > 0.0)) {
      throw InputError(source, range.name, "[" + ShortNumber(range.lower) + ", " + ShortNumber(range.upper) + "]",
                       "expected 0 < lower for a log-uniform parameter");
    }
  }
}

Eigen::MatrixXd SaltelliDesign(const std::vector<ParameterRange>& ranges, int base_samples, bool second_order,
                               std::uint64_t skip_points, const std::string& source) {
  ValidateRanges(ranges, source);
  const int D = static_cast<int>(ranges.size());
  if (D > MaxSaltelliParameters()) {
    throw InputError(source, "parameters", std::to_string(D),
                     "expected at most " + std::to_string(MaxSaltelliParameters()) +
                         " parameters (Sobol sequence of dimension 2D)");
  }
  if (base_samples < 1) {
    throw InputError(source, "samples", std::to_string(base_samples), "expected a base sample count N >= 1");
  }
  const SaltelliLayout layout{D, base_samples, second_order};
  boost::random::sobol sequence(static_cast<std::size_t>(2 * D));
  sequence.discard(static_cast<boost::uintmax_t>(skip_points) * static_cast<boost::uintmax_t>(2 * D));

  Eigen::MatrixXd design(static_cast<Eigen::Index>(layout.RowCount()), D);
  std::vector<double> a(D), b(D);
  auto to_range = [&ranges](int i, double unit) { return ranges[i].FromUnit(unit); };
  for (int j = 0; j < base_samples; ++j) {
    // Coordinates are multiples of 2^-k for the k-th power-of-two stretch of the sequence, so the
    // conversion of the 64-bit integer to double is exact while k ≤ 53.
    for (int i = 0; i < D; ++i) a[i] = std::ldexp(static_cast<double>(sequence()), -64);
    for (int i = 0; i < D; ++i) b[i] = std::ldexp(static_cast<double>(sequence()), -64);
    auto put = [&](std::size_t row, auto pick) {
      for (int i = 0; i < D; ++i) design(static_cast<Eigen::Index>(row), i) = to_range(i, pick(i));
    };
    put(layout.RowA(j), [&](int i) { return a[i]; });
    for (int k = 0; k < D; ++k) put(layout.RowAB(j, k), [&](int i) { return i == k ? b[i] : a[i]; });
    if (second_order) {
      for (int k = 0; k < D; ++k) put(layout.RowBA(j, k), [&](int i) { return i == k ? a[i] : b[i]; });
    }
    put(layout.RowB(j), [&](int i) { return b[i]; });
  }
  return design;
}

double MorrisUnitStep(int levels) {
  GESWEEP_DEMAND(levels >= 2);
  return levels / (2.0 * (levels - 1));
}

Eigen::MatrixXd MorrisDesign(const std::vector<ParameterRange>& ranges, int trajectories, int levels,
                             unsigned long long seed, const std::string& source) {
  ValidateRanges(ranges, source);
  if (trajectories < 1) {
    throw InputError(source, "trajectories", std::to_string(trajectories), "expected at least 1 trajectory");
  }
  if (levels < 2 || levels % 2 != 0) {
    throw InputError(source, "levels", std::to_string(levels),
                     "expected an even number of grid levels >= 2 (4 is usual)");
  }
  const int D = static_cast<int>(ranges.size());
  // With p even, Δ = p/(2(p−1)) is p/2 grid steps: a start on the lower p/2 levels can step up,
  // one on the upper p/2 levels can step down, and every point stays on the grid.
  const int step_levels = levels / 2;
  const double grid = 1.0 / (levels - 1);
  boost::random::mt19937_64 engine(seed);
  Eigen::MatrixXd design(static_cast<Eigen::Index>(trajectories) * (D + 1), D);
  std::vector<int> order(D);
  std::vector<double> point(D);
  std::vector<int> direction(D);
  for (int t = 0; t < trajectories; ++t) {
    for (int i = 0; i < D; ++i) {
      direction[i] = boost::random::uniform_int_distribution<int>(0, 1)(engine) == 0 ? 1 : -1;
      const int level = boost::random::uniform_int_distribution<int>(0, levels - 1 - step_levels)(engine);
      point[i] = (direction[i] > 0 ? level : level + step_levels) * grid;
      order[i] = i;
    }
    // Fisher–Yates with Boost's distribution, so the design is the same on every platform.
    for (int i = D - 1; i > 0; --i) {
      std::swap(order[i], order[boost::random::uniform_int_distribution<int>(0, i)(engine)]);
    }
    auto put = [&](Eigen::Index row) {
      for (int i = 0; i < D; ++i) design(row, i) = ranges[i].FromUnit(point[i]);
    };
    const Eigen::Index first = static_cast<Eigen::Index>(t) * (D + 1);
    put(first);
    for (int k = 0; k < D; ++k) {
      const int i = order[k];
      point[i] = (direction[i] > 0 ? point[i] + step_levels * grid : point[i] - step_levels * grid);
      put(first + 1 + k);
    }
  }
  return design;
}

}  // namespace gesweep
