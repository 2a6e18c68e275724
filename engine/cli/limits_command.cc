// gesweep limits: the one table of limits of every physical input (engine/common/input_limits.h),
// as text, Markdown (docs/limits.md is its output) or JSON.
#include <iostream>
#include <nlohmann/json.hpp>

#include "engine/cli/command.h"
#include "engine/cli/json_util.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"

namespace gesweep {
// `gesweep limits --format json`: one object per entry, its members under their own names.
GESWEEP_JSON_MEMBERS(InputLimit, name, units, minimum, maximum, minimum_exclusive, maximum_exclusive,
                     allows_infinity, whole, reason)
}  // namespace gesweep

namespace gesweep::cli {
namespace {

std::string Bound(const InputLimit& limit, bool upper) {
  const double bound = upper ? limit.maximum : limit.minimum;
  // A whole entry's bounds in full digits (2^53, not 9.007199255e+15).
  if (limit.whole) return std::to_string(static_cast<std::uint64_t>(bound));
  return ShortNumber(bound);
}

std::string Interval(const InputLimit& limit) {
  std::string text = std::string(limit.minimum_exclusive ? "(" : "[") + Bound(limit, false) + ", " +
                     Bound(limit, true) + (limit.maximum_exclusive ? ")" : "]");
  if (limit.allows_infinity) text += " or inf";
  return text;
}

int RunLimits(const std::string& format) {
  RequireFormat(format, {"text", "markdown", "json"});
  if (format == "json") {
    std::cout << nlohmann::json{{"maximum_steps_per_run", kMaximumStepsPerRun},
                                {"maximum_noise_samples_per_run", kMaximumNoiseSamplesPerRun},
                                {"maximum_run_memory_bytes", kMaximumRunMemoryBytes},
                                {"limits", InputLimits()}}
                     .dump(2)
              << "\n";
    return 0;
  }
  if (format == "markdown") {
    // "<" and ">" would be taken for HTML tags (scale.<coefficient>), "|" for a column.
    auto escape = [](std::string_view text) {
      std::string out;
      for (char c : text) {
        out += c == '<' ? "&lt;" : (c == '>' ? "&gt;" : (c == '|' ? "\\|" : std::string(1, c)));
      }
      return out;
    };
    std::cout << "| Input | Range | Units | Why |\n|---|---|---|---|\n";
    for (const InputLimit& limit : InputLimits()) {
      std::cout << "| `" << limit.name << "` | " << Interval(limit) << " | " << limit.units << " | "
                << escape(limit.reason) << " |\n";
    }
    std::cout << "\nAt most " << ShortNumber(kMaximumStepsPerRun)
              << " integration steps per run: duration_s / step_s (RK4), duration_s / max_step_s (dopri5 "
                 "with a largest step), a landing's time limit / max_step_s.\n";
    std::cout << "\nAt most " << ShortNumber(kMaximumNoiseSamplesPerRun)
              << " turbulence noise samples per run: duration_s (or a landing's time limit) / "
                 "turbulence_sample_interval_s, "
              << ShortNumber(kNoiseBytesPerSample) << " bytes each.\n";
    std::cout << "\nAt most " << ApproximateBytes(kMaximumRunMemoryBytes)
              << " of memory per run for its own tables: the noise samples and the time series it keeps.\n";
    return 0;
  }
  std::size_t name_width = 5, range_width = 5;
  for (const InputLimit& limit : InputLimits()) {
    name_width = std::max(name_width, limit.name.size());
    range_width = std::max(range_width, Interval(limit).size() + limit.units.size() + 1);
  }
  for (const InputLimit& limit : InputLimits()) {
    const std::string range = Interval(limit) + " " + std::string(limit.units);
    std::cout << std::string(limit.name) << std::string(name_width + 2 - limit.name.size(), ' ') << range
              << std::string(range_width + 2 - range.size(), ' ') << limit.reason << "\n";
  }
  std::cout << "# at most " << ShortNumber(kMaximumStepsPerRun)
            << " integration steps per run (duration / step, or a landing's time limit / max_step_s)\n";
  std::cout << "# at most " << ShortNumber(kMaximumNoiseSamplesPerRun)
            << " turbulence noise samples per run (duration / turbulence_sample_interval_s), and "
            << ApproximateBytes(kMaximumRunMemoryBytes) << " of memory per run for its noise and series\n";
  return 0;
}

void AddLimitsFlags(CLI::App& app, std::string& format) {
  format = "text";
  app.add_option("--format", format, "text (default), markdown or json");
}

const CommandRegistrar kRegistrar{CommandWith<std::string>(
    "limits",
    "Print the allowed range of every number a flag or a study file takes, with its reason (docs/limits.md)",
    AddLimitsFlags, RunLimits)};

}  // namespace
}  // namespace gesweep::cli
