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

/// The most turbulence noise samples one run may hold (duration / turbulence_sample_interval_s). A
/// turbulent run builds its table of held samples (instants, segments) before its first step, and
/// every sample is an integration step of its own: 1e7 covers the longest run (1e5 s) at the
/// default interval of 0.01 s, and 1000 s at the finest (1e-4 s); 1e9 would take about 32 GB.
inline constexpr double kMaximumNoiseSamplesPerRun = 1e7;

/// Bytes one held noise sample takes while a run is set up and flown: its instant (8), its segment
/// of the field's table (16) and the open loop's elevator of the segment (8).
inline constexpr double kNoiseBytesPerSample = 32;

/// The most memory one run's own tables may take, bytes (its noise table and the time series it
/// keeps until it is stored): 1 GiB, so that a sweep on every core of a node (a run in flight per
/// worker thread) stays within a node's memory. The noise table alone is at most 320 MB.
inline constexpr double kMaximumRunMemoryBytes = 1073741824.0;

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

/// The noise samples a turbulent run of duration_s holds at interval_s: floor(duration / interval).
/// 0 when either is not finite and positive (checked elsewhere).
double NoiseSampleCount(double duration_s, double interval_s);

/// Throws InputError unless NoiseSampleCount(duration_s, interval_s) is at most
/// kMaximumNoiseSamplesPerRun, naming both values, both keys, the count and the memory it would take:
/// "<interval_key> = 0.0001: expected at most 1e+07 turbulence noise samples per run, but
/// <duration_key> = 100000 s / <interval_key> = 0.0001 s = 1e+09 samples (about 32 GB)".
void CheckNoiseSamples(double duration_s, double interval_s, const std::string& source,
                       const std::string& duration_key, const std::string& interval_key);

/// Throws InputError(source, key, value, ...) unless `bytes` is at most kMaximumRunMemoryBytes;
/// `breakdown` says what they are ("1e+08 series samples x 96 bytes"), and goes into the message.
void CheckRunMemory(double bytes, const std::string& breakdown, const std::string& source,
                    const std::string& key, const std::string& value);

/// Bytes in words: "32 GB", "1.07 GB", "320 MB", "4 kB" (decimal units, 3 significant digits).
std::string ApproximateBytes(double bytes);

}  // namespace gesweep
