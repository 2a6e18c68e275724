#include "engine/common/input_limits.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

// Bounds shared by several entries, so that they cannot drift apart.
constexpr double kMaximumHeight_m = 11000.0;  // top of the ISA troposphere the density model uses
constexpr double kMinimumSpeed_mps = 1.0;
constexpr double kMaximumSpeed_mps = 300.0;
constexpr double kMaximumRunDuration_s = 1e5;  // a day of flight: longer is a typo
constexpr double kMaximumStep_s = 10.0;
constexpr double kMinimumStep_s = 1e-6;
constexpr double kMaximumWeight = 1e12;
constexpr double kMaximumExactInteger = 9007199254740992.0;  // 2^53

InputLimit Closed(std::string_view name, std::string_view units, double minimum, double maximum,
                  std::string_view reason) {
  return {.name = name, .units = units, .minimum = minimum, .maximum = maximum, .reason = reason};
}

// (minimum, maximum]: a quantity that must be positive.
InputLimit Positive(std::string_view name, std::string_view units, double maximum, std::string_view reason) {
  InputLimit limit = Closed(name, units, 0.0, maximum, reason);
  limit.minimum_exclusive = true;
  return limit;
}

// [0, maximum], whole numbers only.
InputLimit Whole(std::string_view name, double maximum, std::string_view reason) {
  InputLimit limit = Closed(name, "1", 0.0, maximum, reason);
  limit.whole = true;
  return limit;
}

InputLimit WithInfinity(InputLimit limit) {
  limit.allows_infinity = true;
  return limit;
}

std::vector<InputLimit> BuildTable() {
  constexpr std::string_view kHeightReason =
      "the ISA troposphere the density model uses (docs/model.md section 1); the aircraft's wheel-contact "
      "height is a further lower bound";
  constexpr std::string_view kSpeedReason =
      "the model is incompressible (docs/model.md section 2), so well below Mach 1; below 1 m/s the "
      "dimensional derivatives, which scale with u0 and 1/u0, mean nothing";
  constexpr std::string_view kDurationReason = "a day of flight; the paper's runs last 300 s";
  constexpr std::string_view kStepReason =
      "a step beyond 10 s steps over every mode of Eq. (1); below 1 us it resolves nothing the model "
      "has and the step count limit (1e8 per run) is reached within 100 s";
  constexpr std::string_view kToleranceReason =
      "below 1e-14 the error control asks for more digits than double precision holds";
  std::vector<InputLimit> t;

  // The flight condition and the model (study parameters, CLI flags of modes, boundary, simulate).
  t.push_back(Positive("height_m", "m", kMaximumHeight_m, kHeightReason));
  t.push_back(Closed("speed_mps", "m/s", kMinimumSpeed_mps, kMaximumSpeed_mps, kSpeedReason));
  t.push_back(Closed("scale_factor", "1", -100.0, 100.0,
                     "every scale.<coefficient> and scale.CDo: a factor beyond 100 leaves every table's "
                     "meaning; a negative one flips a sign on purpose"));
  t.push_back(Positive("mass_kg", "kg", 1e6, "from a model airplane to the heaviest airliner (6.4e5 kg)"));
  t.push_back(Positive("pitch_inertia_kgm2", "kg m^2", 1e9, "a Boeing 747's Iy is about 4.4e7 kg m^2"));
  t.push_back(Closed("cg_shift_over_chord", "1", -1.0, 1.0, "beyond one mean chord the CG is off the wing"));

  // The open-loop perturbation (parameters; simulate --elevator-deg, --pulse-s).
  t.push_back(Closed("pulse_amplitude_deg", "deg", -30.0, 30.0,
                     "elevators deflect at most about 30 deg; the linear model means nothing far beyond"));
  t.push_back(Closed("pulse_duration_s", "s", 0.0, kMaximumRunDuration_s, "at most the longest run"));

  // The landing controller (parameters; land flags).
  InputLimit glide = Positive("glide_slope_deg", "deg", 10.0,
                              "the glide path's small-angle kinematics (docs/model.md section 8); steep "
                              "approaches are 5.5 to 7 deg");
  t.push_back(glide);
  t.push_back(Positive("flare_height_m", "m", 1000.0, "a flare starts within tens of metres of the ground"));
  t.push_back(Positive("flare_time_constant_s", "s", 1e4, "the flare's time constant is seconds to minutes"));
  t.push_back(Closed("q_weights", "1", 0.0, kMaximumWeight,
                     "every q_weights.<state>: beyond 1e12 the Riccati equation is ill-conditioned in double "
                     "precision"));
  t.push_back(Closed("r_weight", "rad^2", 1e-12, kMaximumWeight,
                     "as q_weights; R must be positive for the LQR problem to have a solution"));

  // The moving atmosphere (run parameters of open_loop and landing; flags of simulate and land).
  t.push_back(Closed("wind_20ft_mps", "m/s", -50.0, 50.0,
                     "MIL-F-8785C's low-altitude model is written for winds up to about 45 kt (23 m/s) at "
                     "20 ft; beyond 50 m/s no airplane of this model lands"));
  t.push_back(Closed("turbulence_sigma_w_mps", "m/s", 0.0, 50.0,
                     "the specification's severe turbulence at low altitude is sigma_w of about 3 m/s; as "
                     "wind_20ft_mps (left out: 0.1 |wind_20ft_mps|)"));
  t.push_back(Closed("gust_amplitude_mps", "m/s", -50.0, 50.0,
                     "the specification's design gusts are a few m/s; as wind_20ft_mps"));
  t.push_back(Positive("gust_half_length_m", "m", 1e4,
                       "the specification's half-lengths are tens to hundreds of metres; 0 is a step"));
  t.push_back(Closed("gust_start_s", "s", 0.0, kMaximumRunDuration_s, "within the longest run"));
  t.push_back(Closed("turbulence_sample_interval_s", "s", 1e-4, 1.0,
                     "the held noise loses the band above about 0.35 per interval (docs/disturbance.md): "
                     "beyond 1 s it misses the short period; below 0.1 ms it costs without changing "
                     "anything the model has"));
  t.push_back(Whole("seed", kMaximumExactInteger,
                    "2^53: every whole number up to it is exact as a double, so a seed reads back from an "
                    "archive, JSON or Python as it was given"));
  t.push_back(Whole("run_index", kMaximumExactInteger,
                    "a run's index in its design (simulate and land replay run i of a sweep with it); as "
                    "seed"));

  // The verification models' inputs.
  t.push_back(Closed("verification_input", "1", -1e9, 1e9,
                     "x1..x8 of the test functions: dimensionless, bounded so that their sums and powers "
                     "stay finite"));

  // Settings of the open_loop analysis and flags of gesweep simulate.
  t.push_back(Positive("open_loop.duration_s", "s", kMaximumRunDuration_s, kDurationReason));
  t.push_back(Closed("open_loop.step_s", "s", kMinimumStep_s, kMaximumStep_s, kStepReason));
  t.push_back(Closed("open_loop.max_step_s", "s", 0.0, kMaximumStep_s,
                     "dopri5's largest step (0: no limit); as open_loop.step_s"));
  t.push_back(Closed("open_loop.input_start_s", "s", 0.0, kMaximumRunDuration_s, "within the longest run"));
  t.push_back(Closed("open_loop.initial_delta_u_mps", "m/s", -kMaximumSpeed_mps, kMaximumSpeed_mps,
                     "an offset within the speed range"));
  t.push_back(Closed("open_loop.initial_delta_w_mps", "m/s", -kMaximumSpeed_mps, kMaximumSpeed_mps,
                     "an offset within the speed range"));
  t.push_back(Closed("open_loop.initial_pitch_rate_degps", "deg/s", -360.0, 360.0,
                     "a turn a second is far outside the small-perturbation model"));
  t.push_back(
      Closed("open_loop.initial_pitch_deg", "deg", -90.0, 90.0, "the pitch angle of a flying airplane"));
  t.push_back(Closed("open_loop.initial_delta_h_m", "m", -kMaximumHeight_m, kMaximumHeight_m,
                     "an offset within the height range"));

  // Shared by open_loop and landing (and their flags).
  t.push_back(Closed("relative_tolerance", "1", 1e-14, 1.0, kToleranceReason));
  t.back().maximum_exclusive = true;
  t.push_back(Closed("absolute_tolerance", "1", 1e-15, 1e3,
                     "below 1e-15 the error control asks for more digits than double precision holds on "
                     "states of order 1"));
  t.push_back(Closed("output_dt_s", "s", kMinimumStep_s, 1e4,
                     "the sampling interval of stored series; as open_loop.step_s"));

  // Settings of the landing analysis and flags of gesweep land.
  t.push_back(Closed("landing.max_step_s", "s", kMinimumStep_s, kMaximumStep_s, kStepReason));
  t.push_back(Positive("landing.time_limit_s", "s", kMaximumRunDuration_s, kDurationReason));
  t.push_back(Closed("landing.start_pitch_deg", "deg", -90.0, 90.0,
                     "and below divergence_pitch_deg, which ends the run"));
  t.push_back(Closed("landing.start_glide_path_offset_m", "m", -1000.0, 1000.0,
                     "a glide-slope receiver captures the beam within a few hundred metres"));
  t.push_back(WithInfinity(Positive("landing.design_height_m", "m", kMaximumHeight_m,
                                    "as height_m; inf designs on the free-flight row")));
  t.push_back(Positive("landing.actuator_pole_per_s", "1/s", 1e4,
                       "an actuator faster than 1e4 1/s makes the closed loop stiff beyond dopri5's reach"));
  t.push_back(Positive("landing.compensator_pole_per_s", "1/s", 1e4, "as landing.actuator_pole_per_s"));
  InputLimit elevator_min = Closed("landing.elevator_min_deg", "deg", -90.0, 0.0,
                                   "a lower limit below neutral; beyond 90 deg is not an elevator");
  elevator_min.maximum_exclusive = true;
  t.push_back(elevator_min);
  t.push_back(Positive("landing.elevator_max_deg", "deg", 90.0,
                       "an upper limit above neutral; beyond 90 deg is not an elevator"));
  t.push_back(Closed("landing.plant_fixed_reference_height_m", "m", 0.0, kMaximumHeight_m, kHeightReason));
  t.push_back(Positive("landing.divergence_pitch_deg", "deg", 90.0,
                       "|pitch| beyond it ends the run as diverged: the small-angle model means nothing"));
  t.push_back(
      Closed("landing.flare_asymptote_m", "m", 0.0, 1000.0,
             "the height the flare's exponential tends to: at most the largest flare height, and below "
             "the run's flare_height_m"));
  t.push_back(Positive("landing.series_duration_s", "s", kMaximumRunDuration_s, kDurationReason));

  // Settings of the estimators (sensitivity and dispersion flags).
  t.push_back(Whole("bootstrap_resamples", 1e6,
                    "bootstrap resamples of sensitivity's intervals (0: none): beyond 1e6 the percentiles "
                    "change by less than their own sampling error, at the cost of a full pass each"));
  InputLimit level = Closed("confidence_level", "1", 0.0, 1.0,
                            "the level of a confidence interval: a probability strictly between 0 and 1");
  level.minimum_exclusive = true;
  level.maximum_exclusive = true;
  t.push_back(level);

  // Settings of the commands themselves (flags only).
  t.push_back(
      Whole("threads", 4096, "worker threads of a sweep (left out: every core); beyond 4096 is a typo"));
  t.back().minimum = 1;
  t.push_back(Whole("lanes", 8,
                    "runs a sweep computes at once in the lanes of SIMD vectors: 1, 2, 4 or 8 (the widths of "
                    "the open loop's lanes); 1 is one at a time"));
  t.back().minimum = 1;
  t.push_back(Whole("ranks_per_node", 4096,
                    "with MPI, the shard writers per node (0: $GESWEEP_RANKS_PER_NODE, else the ranks "
                    "sharing a machine); as threads"));
  t.push_back(Positive("dry_run_budget_s", "s", 600,
                       "the wall time a dry run's measurement may take: it is an estimate, not a run"));
  t.push_back(Whole("query.memory_mb", 1048576,
                    "memory for exact medians and quantiles, MiB: 1 MiB to 1 TiB; past it, more passes"));
  t.back().minimum = 1;
  t.push_back(Whole("query.limit", kMaximumExactInteger, "rows (or groups) shown: a count, as seed"));
  t.push_back(Whole("max_groups", 1e8,
                    "groups a query's aggregate or a dispersion holds in memory, about 100 bytes each per "
                    "statistic: 1e8 is about 10 GB"));
  t.back().minimum = 1;

  // Settings of the boundary analysis.
  t.push_back(Closed("boundary.tolerance_m", "m", 1e-9, 1e-3,
                     "the boundary is refined to at most 1 mm; below 1 nm bisection resolves nothing"));
  return t;
}

}  // namespace

const std::vector<InputLimit>& InputLimits() {
  static const std::vector<InputLimit> table = BuildTable();
  return table;
}

const InputLimit* FindInputLimit(std::string_view name) {
  for (const InputLimit& limit : InputLimits()) {
    if (limit.name == name) return &limit;
  }
  return nullptr;
}

const InputLimit& RequireInputLimit(std::string_view name) {
  const InputLimit* limit = FindInputLimit(name);
  GESWEEP_DEMAND(limit != nullptr);
  return *limit;
}

bool WithinLimit(const InputLimit& limit, double value) {
  if (limit.allows_infinity && value == std::numeric_limits<double>::infinity()) return true;
  if (!std::isfinite(value)) return false;
  if (limit.whole && value != std::floor(value)) return false;
  const bool above_minimum = limit.minimum_exclusive ? value > limit.minimum : value >= limit.minimum;
  const bool below_maximum = limit.maximum_exclusive ? value < limit.maximum : value <= limit.maximum;
  return above_minimum && below_maximum;
}

namespace {

// A whole bound in full digits (every bound of a whole entry is at most 2^53, exact as a double).
std::string WholeText(double bound) { return std::to_string(static_cast<std::uint64_t>(bound)); }

}  // namespace

std::string DescribeLimit(const InputLimit& limit) {
  if (limit.whole) {
    return std::string("a whole number in ") + (limit.minimum_exclusive ? "(" : "[") +
           WholeText(limit.minimum) + ", " + WholeText(limit.maximum) + (limit.maximum_exclusive ? ")" : "]");
  }
  std::string text = std::string("a number in ") + (limit.minimum_exclusive ? "(" : "[") +
                     ShortNumber(limit.minimum) + ", " + ShortNumber(limit.maximum) +
                     (limit.maximum_exclusive ? ")" : "]");
  if (limit.units != "1") text += " " + std::string(limit.units);
  if (limit.allows_infinity) text += ", or inf";
  return text;
}

std::string LimitProblem(const InputLimit& limit, double value) {
  if (WithinLimit(limit, value)) return "";
  return "expected " + DescribeLimit(limit) + " (" + std::string(limit.reason) + ")";
}

void CheckInputLimit(std::string_view limit_name, double value, const std::string& source,
                     const std::string& key) {
  const std::string problem = LimitProblem(RequireInputLimit(limit_name), value);
  if (!problem.empty()) throw InputError(source, key, ShortNumber(value), problem);
}

std::uint64_t ParseExactInteger(std::string_view text, std::string_view limit_name, const std::string& source,
                                const std::string& key) {
  const InputLimit& limit = RequireInputLimit(limit_name);
  GESWEEP_DEMAND(limit.whole && limit.minimum >= 0 && limit.maximum <= kMaximumExactInteger);
  const auto refuse = [&](std::string_view how) -> std::uint64_t {
    throw InputError(
        source, key, std::string(text),
        "expected " + DescribeLimit(limit) + std::string(how) + " (" + std::string(limit.reason) + ")");
  };
  const bool digits =
      !text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits) return refuse(" written in digits (no sign, fraction or exponent)");
  // Digits only, so the value is exact as soon as it has at most 16 of them (2^53 has 16); more,
  // after leading zeros, is past every whole entry's maximum.
  const std::size_t first = std::min(text.find_first_not_of('0'), text.size());
  if (text.size() - first > 16) return refuse("");
  std::uint64_t value = 0;
  for (std::size_t i = first; i < text.size(); ++i)
    value = value * 10 + static_cast<std::uint64_t>(text[i] - '0');
  const auto minimum = static_cast<std::uint64_t>(limit.minimum);
  const auto maximum = static_cast<std::uint64_t>(limit.maximum);
  const bool above = limit.minimum_exclusive ? value > minimum : value >= minimum;
  const bool below = limit.maximum_exclusive ? value < maximum : value <= maximum;
  if (!above || !below) return refuse("");
  return value;
}

void CheckStepCount(double duration_s, double step_s, const std::string& source,
                    const std::string& duration_key, const std::string& step_key) {
  if (!(step_s > 0.0) || !std::isfinite(step_s) || !std::isfinite(duration_s)) return;
  const double steps = duration_s / step_s;
  if (steps <= kMaximumStepsPerRun) return;
  throw InputError(source, step_key, ShortNumber(step_s),
                   "expected at most " + ShortNumber(kMaximumStepsPerRun) +
                       " integration steps per run, but " + duration_key + " = " + ShortNumber(duration_s) +
                       " s / " + step_key + " = " + ShortNumber(step_s) + " s = " + ShortNumber(steps) +
                       " steps; take a larger step or a shorter run (docs/limits.md)");
}

double NoiseSampleCount(double duration_s, double interval_s) {
  if (!(interval_s > 0.0) || !std::isfinite(interval_s) || !(duration_s > 0.0) || !std::isfinite(duration_s))
    return 0.0;
  return std::floor(duration_s / interval_s);
}

std::string ApproximateBytes(double bytes) {
  const char* units[] = {"bytes", "kB", "MB", "GB", "TB", "PB"};
  int unit = 0;
  while (unit < 5 && bytes >= 1000.0) {
    bytes /= 1000.0;
    ++unit;
  }
  char text[48];
  std::snprintf(text, sizeof text, "%.3g %s", bytes, units[unit]);
  return text;
}

void CheckNoiseSamples(double duration_s, double interval_s, const std::string& source,
                       const std::string& duration_key, const std::string& interval_key) {
  const double samples = NoiseSampleCount(duration_s, interval_s);
  if (samples <= kMaximumNoiseSamplesPerRun) return;
  throw InputError(source, interval_key, ShortNumber(interval_s),
                   "expected at most " + ShortNumber(kMaximumNoiseSamplesPerRun) +
                       " turbulence noise samples per run, but " + duration_key + " = " +
                       ShortNumber(duration_s) + " s / " + interval_key + " = " + ShortNumber(interval_s) +
                       " s = " + ShortNumber(samples) + " samples (about " +
                       ApproximateBytes(samples * kNoiseBytesPerSample) +
                       " of memory and as many integration " +
                       "steps); take a larger sample interval or a shorter run (docs/limits.md)");
}

void CheckRunMemory(double bytes, const std::string& breakdown, const std::string& source,
                    const std::string& key, const std::string& value) {
  if (bytes <= kMaximumRunMemoryBytes) return;
  throw InputError(source, key, value,
                   "expected at most " + ApproximateBytes(kMaximumRunMemoryBytes) +
                       " of memory per run, but the run would hold " + breakdown + " = about " +
                       ApproximateBytes(bytes) +
                       "; take a larger interval or a shorter run (docs/limits.md)");
}

}  // namespace gesweep
