// gesweep sensitivity: global sensitivity of one output of a sweep's archive (docs/sensitivity.md,
// "gesweep sensitivity"): Sobol' indices from a sobol (Saltelli) design, Morris elementary effects
// from a morris design; prints the table (or JSON) and writes /analysis/sensitivity/<output>/ into
// the archive.
//   gesweep sensitivity ARCHIVE --output NAME [--method sobol|morris] [--bootstrap 1000] [--seed S]
//       [--confidence-level 0.95] [--failed-runs drop_blocks|error] [--format table|json] [--no-write]
// Exit codes: 0 ok; 2 bad input (no such archive or output, wrong design for the method, archive in
// use or incomplete); 3 runs without a value and --failed-runs error; 1 an I/O error or a degenerate
// output (constant, or fewer than two usable blocks).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/model_flags.h"
#include "engine/common/errors.h"
#include "engine/products/archive_sensitivity.h"
#include "engine/products/sensitivity_group.h"

namespace gesweep::cli {
namespace {

struct SensitivityFlags {
  std::string archive;
  std::string output;
  std::string method;  // empty: the design's own
  int bootstrap = BootstrapOptions{}.resamples;
  std::uint64_t seed = BootstrapOptions{}.seed;
  double confidence_level = BootstrapOptions{}.confidence_level;
  FailedRunPolicy failed_runs = FailedRunPolicy::kDropBlocks;
  TableOrJson format = TableOrJson::kAligned;
  bool no_write = false;
  DescribedFlags described;

  /// The settings whose flag is their key's name (DescribedFlags, added by CommandWith); the archive,
  /// the output and the method (none: the design's own) are added by hand.
  template <class V>
  void Describe(V& v) {
    v(Field("bootstrap", &bootstrap)
          .Limit("bootstrap_resamples")
          .Doc("Bootstrap resamples for the intervals (0: none)"));
    v(Field("seed", &seed).Limit("seed").Doc("Seed of the bootstrap: same seed, same intervals"));
    v(Field("confidence_level", &confidence_level).Limit("confidence_level").Doc("Level of the intervals"));
    v(Field("no_write", &no_write).Doc("Print only; leave the archive untouched"));
    v(Field("failed_runs", &failed_runs)
          .Doc("Runs without a value (failed, or NaN such as no boundary): drop_blocks leaves out every "
               "Saltelli block / Morris trajectory that holds one, error stops (exit 3)"));
    v(Field("format", &format).Doc("Output: a table for a person, JSON for a program"));
  }
};

std::string CommandLine(const SensitivityFlags& flags) {
  std::ostringstream line;
  line << "gesweep sensitivity " << flags.archive << " --output " << flags.output;
  if (!flags.method.empty()) line << " --method " << flags.method;
  line << " --bootstrap " << flags.bootstrap << " --seed " << flags.seed << " --confidence-level "
       << ShortNumber(flags.confidence_level) << " --failed-runs " << ToString(flags.failed_runs);
  return line.str();
}

std::string Fixed(double value, int decimals = 4) {
  if (!std::isfinite(value)) return FormatNumber(value);
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

std::string General(double value) { return FormatNumber(value, 5); }

std::string Interval(const ConfidenceInterval& ci, std::string (*format)(double, int), int decimals) {
  return "[" + format(ci.lower, decimals) + ", " + format(ci.upper, decimals) + "]";
}

std::string GeneralInterval(const ConfidenceInterval& ci) {
  return "[" + General(ci.lower) + ", " + General(ci.upper) + "]";
}

// The key order (output, method, n, indices; parameter, first_order, ...) is kept.
using Json = nlohmann::ordered_json;

Json Number(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

Json JsonInterval(const ConfidenceInterval& ci) { return Json::array({Number(ci.lower), Number(ci.upper)}); }

const BootstrapOptions& BootstrapOf(const ArchiveSensitivity& r) {
  return r.method == SensitivityMethod::kSobol ? r.sobol.bootstrap : r.morris.bootstrap;
}

std::string MissingSummary(const ArchiveSensitivity& r) {
  const std::int64_t missing = r.runs_failed + r.runs_without_value;
  std::string text = std::to_string(missing) + " run" + (missing == 1 ? "" : "s") +
                     " without a value: " + std::to_string(r.runs_failed) + " failed, " +
                     std::to_string(r.runs_without_value) + " ok with a non-finite output";
  if (!r.first_missing_message.empty())
    text += "; first, row " + std::to_string(r.first_missing_row) + ": " + r.first_missing_message;
  return text;
}

Json ToJson(const ArchiveSensitivity& r, bool written) {
  const BootstrapOptions& bootstrap = BootstrapOf(r);
  Json out;
  out["output"] = r.output.name;
  out["method"] = std::string(ToString(r.method));
  out["n"] = r.n();
  Json indices = Json::array();
  for (std::size_t i = 0; i < r.parameters.size(); ++i) {
    if (r.method == SensitivityMethod::kSobol) {
      indices.push_back({{"parameter", r.parameters[i]},
                         {"first_order", Number(r.sobol.first_order[i])},
                         {"first_order_ci", JsonInterval(r.sobol.first_order_ci[i])},
                         {"total", Number(r.sobol.total[i])},
                         {"total_ci", JsonInterval(r.sobol.total_ci[i])}});
    } else {
      indices.push_back({{"parameter", r.parameters[i]},
                         {"mu", Number(r.morris.mu[i])},
                         {"mu_star", Number(r.morris.mu_star[i])},
                         {"mu_star_ci", JsonInterval(r.morris.mu_star_ci[i])},
                         {"sigma", Number(r.morris.sigma[i])}});
    }
  }
  out["indices"] = indices;
  // Beyond the fields: where the numbers come from and what was left out.
  out["output_path"] = r.output.path;
  out["output_units"] = r.output.units;
  out["archive"] = r.archive_path;
  out["group"] = written ? Json(SensitivityGroupPath(r.output)) : Json(nullptr);
  out["d"] = r.parameters.size();
  out["run_count"] = r.run_count;
  out["blocks_used"] = r.blocks_used();
  out["blocks_dropped"] = r.blocks_dropped();
  out["runs_failed"] = r.runs_failed;
  out["runs_without_value"] = r.runs_without_value;
  out["failed_runs"] = std::string(ToString(r.failed_runs));
  out["bootstrap"] = {{"resamples", bootstrap.resamples},
                      {"seed", bootstrap.seed},
                      {"confidence_level", bootstrap.confidence_level}};
  if (r.method == SensitivityMethod::kSobol) {
    out["second_order"] = r.sobol.layout.second_order;
    if (r.sobol.layout.second_order) {
      Json pairs = Json::array();
      const auto D = static_cast<Eigen::Index>(r.parameters.size());
      for (Eigen::Index i = 0; i < D; ++i) {
        for (Eigen::Index j = i + 1; j < D; ++j) {
          pairs.push_back(
              {{"parameters",
                {r.parameters[static_cast<std::size_t>(i)], r.parameters[static_cast<std::size_t>(j)]}},
               {"second_order", Number(r.sobol.second_order(i, j))},
               {"second_order_ci",
                JsonInterval({r.sobol.second_order_ci_lower(i, j), r.sobol.second_order_ci_upper(i, j)})}});
        }
      }
      out["second_order_indices"] = pairs;
    }
  } else {
    out["levels"] = r.morris_levels;
  }
  return out;
}

void PrintSobol(const ArchiveSensitivity& r) {
  const SobolIndices& s = r.sobol;
  const BootstrapOptions& bootstrap = s.bootstrap;
  const std::string level = ShortNumber(100.0 * bootstrap.confidence_level) + " %";
  std::cout << "# Sobol' indices of " << r.output.name << " [" << r.output.units << "] in " << r.archive_path
            << " (study " << r.study_name << ")\n";
  std::cout << "# Saltelli design: N = " << s.layout.base_samples
            << " base samples, D = " << s.layout.parameter_count << " parameters, "
            << (s.layout.second_order ? "with" : "no") << " second order; " << r.run_count << " runs\n";
  std::cout << "# blocks: " << s.blocks_used << " used, " << s.blocks_dropped << " dropped ("
            << MissingSummary(r) << ")\n";
  std::cout << "# first order: Saltelli et al. (2010); total: Jansen (1999); " << level
            << " bootstrap intervals, " << bootstrap.resamples << " resamples of the base samples, seed "
            << bootstrap.seed << "\n";
  const int w = 22;
  std::cout << "  " << std::left << std::setw(w) << "parameter" << std::right << std::setw(9) << "S1"
            << "  " << std::left << std::setw(20) << "S1 interval" << std::right << std::setw(9) << "ST"
            << "  " << std::left << "ST interval"
            << "\n";
  double sum_first = 0, sum_total = 0;
  for (std::size_t i = 0; i < r.parameters.size(); ++i) {
    sum_first += s.first_order[i];
    sum_total += s.total[i];
    std::cout << "  " << std::left << std::setw(w) << r.parameters[i] << std::right << std::setw(9)
              << Fixed(s.first_order[i]) << "  " << std::left << std::setw(20)
              << Interval(s.first_order_ci[i], Fixed, 4) << std::right << std::setw(9) << Fixed(s.total[i])
              << "  " << Interval(s.total_ci[i], Fixed, 4) << "\n";
  }
  std::cout << "  " << std::left << std::setw(w) << "sum" << std::right << std::setw(9) << Fixed(sum_first)
            << "  " << std::setw(20) << "" << std::setw(9) << Fixed(sum_total) << "\n";
  if (!s.layout.second_order) return;
  std::cout << "# second order S_ij (i < j), " << level << " intervals\n";
  const auto D = static_cast<Eigen::Index>(r.parameters.size());
  auto pair_name = [&r](Eigen::Index i, Eigen::Index j) {
    return r.parameters[static_cast<std::size_t>(i)] + " x " + r.parameters[static_cast<std::size_t>(j)];
  };
  int pair_width = w;
  for (Eigen::Index i = 0; i < D; ++i) {
    for (Eigen::Index j = i + 1; j < D; ++j)
      pair_width = std::max<int>(pair_width, static_cast<int>(pair_name(i, j).size()) + 1);
  }
  for (Eigen::Index i = 0; i < D; ++i) {
    for (Eigen::Index j = i + 1; j < D; ++j) {
      std::cout << "  " << std::left << std::setw(pair_width) << pair_name(i, j) << std::right << std::setw(9)
                << Fixed(s.second_order(i, j)) << "  "
                << Interval({s.second_order_ci_lower(i, j), s.second_order_ci_upper(i, j)}, Fixed, 4) << "\n";
    }
  }
}

void PrintMorris(const ArchiveSensitivity& r) {
  const MorrisIndices& m = r.morris;
  const BootstrapOptions& bootstrap = m.bootstrap;
  std::cout << "# Morris elementary effects of " << r.output.name << " [" << r.output.units << "] in "
            << r.archive_path << " (study " << r.study_name << ")\n";
  std::cout << "# design: r = " << m.trajectories << " trajectories, p = " << r.morris_levels
            << " levels, delta = " << General(r.morris_delta) << ", D = " << m.parameter_count << "; "
            << r.run_count << " runs\n";
  std::cout << "# trajectories: " << m.trajectories_used << " used, " << m.trajectories_dropped
            << " dropped (" << MissingSummary(r) << ")\n";
  std::cout << "# effects in " << r.output.units << " per full range of the parameter; mu* "
            << ShortNumber(100.0 * bootstrap.confidence_level) << " % bootstrap interval, "
            << bootstrap.resamples << " resamples of the trajectories, seed " << bootstrap.seed << "\n";
  const int w = 22;
  std::cout << "  " << std::left << std::setw(w) << "parameter" << std::right << std::setw(12) << "mu"
            << std::setw(12) << "mu*"
            << "  " << std::left << std::setw(26) << "mu* interval" << std::right << std::setw(12) << "sigma"
            << "\n";
  for (std::size_t i = 0; i < r.parameters.size(); ++i) {
    std::cout << "  " << std::left << std::setw(w) << r.parameters[i] << std::right << std::setw(12)
              << General(m.mu[i]) << std::setw(12) << General(m.mu_star[i]) << "  " << std::left
              << std::setw(26) << GeneralInterval(m.mu_star_ci[i]) << std::right << std::setw(12)
              << General(m.sigma[i]) << "\n";
  }
}

int Sensitivity(const SensitivityFlags& flags) {
  ArchiveSensitivityOptions options;
  if (!flags.method.empty()) {
    options.method = ParseSensitivityMethod(flags.method);
    if (!options.method)
      throw InputError("command line", "--method", flags.method, "expected sobol or morris");
  }
  options.failed_runs = flags.failed_runs;
  // --seed and --bootstrap are within their whole entries of the limits table (parsed exactly).
  options.bootstrap.resamples = flags.bootstrap;
  options.bootstrap.seed = flags.seed;
  options.bootstrap.confidence_level = flags.confidence_level;
  ValidateBootstrapOptions(options.bootstrap, "command line");

  // The engine names the request's fields (the source is the archive): this command's flags.
  return GuardArchive({{"output", "--output"}, {"method", "--method"}}, [&] {
    ProductArchive archive = OpenProductArchive(flags.archive, flags.no_write, "sensitivity");
    const ArchiveSensitivity result = AnalyzeArchiveOutput(archive.reader, flags.output, options);
    archive.reader.Close();
    if (result.status != SensitivityStatus::kOk) {
      std::cerr << "gesweep: error: " << flags.archive << ": " << result.message
                << (result.failed_runs_remedy.empty()
                        ? ""
                        : ", or pass --failed-runs drop_blocks to " + result.failed_runs_remedy)
                << "\n";
      return result.status == SensitivityStatus::kStoppedOnFailedRuns ? 3 : 1;
    }
    const bool written = archive.lock.has_value();
    if (written) WriteSensitivityGroup(flags.archive, result, CommandLine(flags));
    if (flags.format == TableOrJson::kJson) {
      std::cout << ToJson(result, written).dump(2) << "\n";
    } else {
      if (result.method == SensitivityMethod::kSobol) {
        PrintSobol(result);
      } else {
        PrintMorris(result);
      }
      if (written)
        std::cout << "# written to " << flags.archive << ": /" << SensitivityGroupPath(result.output) << "\n";
    }
    return 0;
  });
}

void AddSensitivityFlags(CLI::App& app, SensitivityFlags& flags) {
  AddArchiveArgument(app, flags.archive, "Archive of a sweep with a sobol or morris design");
  app.add_option(
         "--output", flags.output,
         "Output column: a name (height_m, ishigami), a path below results/ (boundary/height_m) or the "
         "full path (results/boundary/height_m)")
      ->required();
  app.add_option("--method", flags.method, "sobol or morris (default: the one the design was made for)");
}

const CommandRegistrar kRegistrar{CommandWith<SensitivityFlags>(
    "sensitivity",
    "Sobol' indices or Morris effects of one output of a sobol/morris sweep's archive; writes them into "
    "/analysis/sensitivity/<output>/ (exit 3: runs without a value and --failed-runs error)",
    AddSensitivityFlags, Sensitivity)};

}  // namespace
}  // namespace gesweep::cli
