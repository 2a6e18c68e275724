#include "engine/modal/boundary.h"

#include <algorithm>
#include <boost/math/tools/toms748_solve.hpp>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "engine/common/errors.h"
#include "engine/modal/modal_analysis.h"

namespace gesweep {
namespace {

std::vector<double> ScanHeights(const std::vector<double>& table_heights, double lower, double upper,
                                int samples_per_segment) {
  std::vector<double> knots{lower};
  for (double h : table_heights) {
    if (h > lower && h < upper) knots.push_back(h);
  }
  knots.push_back(upper);
  std::vector<double> heights;
  for (std::size_t i = 0; i + 1 < knots.size(); ++i) {
    for (int j = 0; j <= samples_per_segment; ++j) {
      heights.push_back(knots[i] + (knots[i + 1] - knots[i]) * j / (samples_per_segment + 1.0));
    }
  }
  heights.push_back(upper);
  return heights;
}

std::string FormatMetres(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value << " m";
  return out.str();
}

}  // namespace

BoundaryResult FindBoundary(const LongitudinalModel& model, double speed_mps, const BoundaryOptions& options) {
  const Aircraft& aircraft = model.aircraft();
  BoundaryResult result;
  result.speed_mps = speed_mps;
  result.lower_height_m =
      std::isnan(options.lower_height_m) ? aircraft.wheel_contact_height_m : options.lower_height_m;
  result.upper_height_m =
      std::isnan(options.upper_height_m) ? aircraft.table_heights_m.back() : options.upper_height_m;
  GESWEEP_DEMAND(result.upper_height_m > result.lower_height_m);

  auto sigma = [&](double height_m) {
    ++result.margin_evaluations;
    return StabilityMargin(model, height_m, speed_mps);
  };

  const std::vector<double> heights = ScanHeights(aircraft.table_heights_m, result.lower_height_m,
                                                  result.upper_height_m, options.samples_per_segment);
  std::vector<double> margins;
  margins.reserve(heights.size());
  for (double h : heights) {
    const double s = sigma(h);
    if (!std::isfinite(s)) {
      result.reason = "stability margin is not finite at H = " + FormatMetres(h);
      return result;
    }
    margins.push_back(s);
  }

  for (std::size_t i = heights.size() - 1; i-- > 0;) {
    const double a = heights[i], b = heights[i + 1];
    const double sa = margins[i], sb = margins[i + 1];
    if ((sa < 0) == (sb < 0)) continue;
    SigmaCrossing crossing;
    crossing.stable_above = sb < 0;
    if (sa == 0.0 || sb == 0.0) {
      crossing.height_m = sa == 0.0 ? a : b;
    } else {
      std::uintmax_t max_iterations = 200;
      const double tolerance = options.tolerance_m;
      auto [low, high] = boost::math::tools::toms748_solve(
          sigma, a, b, sa, sb,
          [tolerance](double x, double y) { return std::abs(y - x) <= tolerance; }, max_iterations);
      crossing.height_m = 0.5 * (low + high);
      crossing.bracket_width_m = high - low;
    }
    result.crossings.push_back(crossing);
  }

  for (const auto& crossing : result.crossings) {
    if (crossing.stable_above) {
      result.height_m = crossing.height_m;
      result.height_over_span = crossing.height_m / aircraft.wingspan_m;
      break;
    }
  }
  if (!result.height_m) {
    const bool all_stable = std::all_of(margins.begin(), margins.end(), [](double s) { return s < 0; });
    const bool all_unstable = std::all_of(margins.begin(), margins.end(), [](double s) { return s >= 0; });
    const std::string range = FormatMetres(result.lower_height_m) + " to " + FormatMetres(result.upper_height_m);
    if (all_stable) {
      result.reason = "stable at every height from " + range;
    } else if (all_unstable) {
      result.reason = "unstable at every height from " + range;
    } else {
      result.reason = "no height in " + range + " has unstable below and stable above";
    }
  }
  return result;
}

}  // namespace gesweep
