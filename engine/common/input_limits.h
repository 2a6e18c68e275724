#pragma once
/// The one table of limits of every physical input (docs/limits.md, `gesweep limits`).
///
/// Each quantity a person gives a value for -- a study parameter ([parameters], [design]), an
/// analysis setting ([analyses.<name>]) or a command-line flag -- has exactly one range here, with a
/// one-line reason. The study validator, the analyses' settings and every CLI flag check values
/// against this table, so a value the study schema refuses is refused on the command line too, with
/// the same words. The table is data: `gesweep limits` prints it, docs/limits.md is that output, and
/// the parameter catalogue (engine/analyses/parameter_catalog.h) takes its ranges from it.
///
/// Names: a study parameter's own name ("speed_mps", "height_m"); an analysis setting as
/// "<analysis>.<key>" ("open_loop.step_s", "landing.max_step_s"); a setting shared by two analyses
/// with one meaning by its key alone ("relative_tolerance"); a family of parameters by its family
/// ("scale_factor" for every scale.<coefficient>).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace gesweep {

/// The most integration steps one run may take: a run whose step count (duration / step, or a
/// landing's time limit / largest step) exceeds it is refused before it starts. 1e8 RK4 steps of
/// Eq. (1) take about 7 s on one core (docs/limits.md); more is almost certainly a typo in a step.
inline constexpr double kMaximumStepsPerRun = 1e8;

/// The range of one input quantity. Values are finite unless `allows_infinity` (then +inf also).
struct InputLimit {
  std::string_view name;   ///< see the file comment
  std::string_view units;  ///< "m", "m/s", "deg", "s", "1" for a ratio
  double minimum = 0;
  double maximum = 0;
  bool minimum_exclusive = false;
  bool maximum_exclusive = false;
  bool allows_infinity = false;  ///< +inf accepted too (a height: free flight)
  bool whole = false;            ///< a whole number (a seed, a run index, a count): see ParseExactInteger
  std::string_view reason;       ///< one line: why these bounds
};

/// Every entry, in the order of docs/limits.md.
const std::vector<InputLimit>& InputLimits();

/// The entry of `name`, or null.
const InputLimit* FindInputLimit(std::string_view name);

/// The entry of a name the engine itself uses; GESWEEP_DEMAND that it exists.
const InputLimit& RequireInputLimit(std::string_view name);

/// Whether `value` is allowed.
bool WithinLimit(const InputLimit& limit, double value);

/// The allowed values in words: "a number in [1, 300] m/s", "a number in (0, 11000] m, or inf"; a
/// whole entry's bounds in full digits: "a whole number in [0, 9007199254740992]".
std::string DescribeLimit(const InputLimit& limit);

/// "" when `value` is allowed, else "expected <DescribeLimit> (<reason>)".
std::string LimitProblem(const InputLimit& limit, double value);

/// Throws InputError(source, key, ShortNumber(value), LimitProblem(...)) unless `value` is allowed
/// by the entry `limit_name` (which must exist). `key` is what the person wrote: a flag
/// ("--speed-mps") or a study key ("parameters.speed_mps").
void CheckInputLimit(std::string_view limit_name, double value, const std::string& source,
                     const std::string& key);

/// A whole number the limits table's entry `limit_name` (which must be `whole`) allows, parsed
/// exactly from `text`: one or more decimal digits and nothing else -- no sign, no fraction, no
/// exponent, no space -- never rounded through a double, never wrapped or clamped. Anything else, or
/// a value past the entry's range, throws InputError(source, key, text, "expected a whole number in
/// [0, 9007199254740992] written in digits (<reason>)"). The one parser of seeds, run indices and
/// counts: flags, study files (a TOML integer, as its digits) and Python's keyword arguments (an int).
std::uint64_t ParseExactInteger(std::string_view text, std::string_view limit_name, const std::string& source,
                                const std::string& key);

/// Throws InputError unless duration_s / step_s is at most kMaximumStepsPerRun, naming both values
/// and both keys: "<step_key> = 1e-09: expected at most 1e8 steps per run: <duration_key> = 30 s /
/// <step_key> = 1e-09 s = 3e+10 steps". Does nothing when step_s <= 0 (no bound to check: an
/// adaptive method without a largest step) or either value is not finite (checked elsewhere).
void CheckStepCount(double duration_s, double step_s, const std::string& source,
                    const std::string& duration_key, const std::string& step_key);

}  // namespace gesweep
