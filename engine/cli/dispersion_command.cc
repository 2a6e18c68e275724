// gesweep dispersion: the dispersion of a Monte Carlo sweep's results (docs/dispersion.md): counts,
// moments, percentiles, normal and Gumbel tail fits with their Anderson–Darling statistics, limit
// exceedance probabilities with Wilson and Clopper–Pearson intervals, per group of a column; prints
// them (or JSON) and writes /analysis/dispersion into the archive.
//   gesweep dispersion ARCHIVE [--columns a,b] [--limit 'touchdown_sink_rate_mps>3' ...]
//       [--group-by NAME] [--percentiles 1,50,99] [--tail-probabilities 1e-3,1e-6]
//       [--confidence-level 0.95] [--max-groups 1000] [--format table|json] [--no-write]
// Exit codes: 0 ok; 2 bad input (no such archive or column, archive in use); 1 an I/O error.
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/json_util.h"
#include "engine/cli/model_flags.h"
#include "engine/cli/risk_output.h"
#include "engine/common/errors.h"
#include "engine/products/dispersion.h"
#include "engine/query/run_columns.h"
#include "engine/risk/risk_archive.h"

namespace gesweep {
// The header of a dispersion and the statistics of a column and of a limit in a group, under their
// own names; ToJson adds the settings and groups, the column's name and fits, the limit's text and
// intervals. Non-finite numbers are null.
GESWEEP_JSON_MEMBERS(ColumnDispersion, runs, values, failed, without_value, pending, mean, standard_deviation,
                     minimum, maximum, percentiles, no_spread)
GESWEEP_JSON_MEMBERS(Dispersion, archive, study_name, design_kind, run_count, columns, column_units, group_by)
GESWEEP_JSON_MEMBERS(LimitExceedance, exceed, values, failed, probability, normal_probability,
                     gumbel_probability, gev_probability)
}  // namespace gesweep

namespace gesweep::cli {
namespace {

struct DispersionFlags {
  std::string archive;
  DispersionOptions options;  // its fields are the flags (defaults as the struct's)
  TableOrJson format = TableOrJson::kAligned;
  bool no_write = false;
  DescribedFlags described;

  /// The settings whose flag is their key's name (DescribedFlags, added by CommandWith); the archive,
  /// the limits and the grouping column are added by hand.
  template <class V>
  void Describe(V& v) {
    v(Field("columns", &options.columns)
          .Doc("Result columns (names, paths or wildcards, comma-separated; default: the landing's "
               "touchdown distance past the transmitter, sink rate, speed and pitch, and the flare's "
               "peak elevator when present)"));
    v(Field("percentiles", &options.percentiles).Doc("Percentiles, 0 to 100"));
    v(Field("tail_probabilities", &options.tail_probabilities)
          .Doc("Tail probabilities of the fitted quantiles"));
    v(Field("confidence_level", &options.confidence_level)
          .Limit("confidence_level")
          .Doc("Level of the intervals"));
    v(Field("max_groups", &options.max_groups).Limit("max_groups").Doc("Most groups accepted"));
    v(Field("no_write", &no_write).Doc("Print only; leave the archive untouched"));
    v(Field("format", &format).Doc("Output: a table for a person, JSON for a program"));
  }
};

std::string Join(const std::vector<std::string>& items) {
  std::string text;
  for (const auto& item : items) text += (text.empty() ? "" : ",") + item;
  return text;
}

std::string JoinNumbers(const std::vector<double>& values) {
  std::string text;
  for (double v : values) text += (text.empty() ? "" : ",") + ShortNumber(v);
  return text;
}

std::string CommandLine(const DispersionFlags& flags) {
  std::ostringstream line;
  line << "gesweep dispersion " << flags.archive;
  if (!flags.options.columns.empty()) line << " --columns " << Join(flags.options.columns);
  for (const auto& limit : flags.options.limits) line << " --limit '" << limit << "'";
  if (!flags.options.group_by.empty()) line << " --group-by " << flags.options.group_by;
  line << " --percentiles " << JoinNumbers(flags.options.percentiles) << " --tail-probabilities "
       << JoinNumbers(flags.options.tail_probabilities) << " --confidence-level "
       << ShortNumber(flags.options.confidence_level);
  return line.str();
}

std::string General(double value) { return FormatNumber(value, 6); }

// JSON has no NaN: null.
nlohmann::json Number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

nlohmann::json Numbers(const std::vector<double>& values) {
  nlohmann::json array = nlohmann::json::array();
  for (double v : values) array.push_back(Number(v));
  return array;
}

nlohmann::json FitJson(const TailFit& fit) {
  nlohmann::json j = {{"law", fit.law},
                      {"location", Number(fit.fit.location)},
                      {"scale", Number(fit.fit.scale)},
                      {"anderson_darling", Number(fit.goodness.statistic)},
                      {"critical_values", Numbers(fit.goodness.critical)},
                      {"significance_percent", Numbers(fit.goodness.significance_percent)},
                      {"rejected_at_percent", Number(fit.goodness.rejected_at_percent())}};
  if (fit.law == "gev_max") j["shape"] = Number(fit.shape);
  if (!fit.upper_quantiles.empty()) j["upper_quantiles"] = Numbers(fit.upper_quantiles);
  if (!fit.lower_quantiles.empty()) j["lower_quantiles"] = Numbers(fit.lower_quantiles);
  return j;
}

nlohmann::json ToJson(const Dispersion& d, bool written) {
  nlohmann::json groups = nlohmann::json::array();
  for (const auto& g : d.groups) {
    nlohmann::json columns = nlohmann::json::array();
    for (std::size_t c = 0; c < d.columns.size(); ++c) {
      const ColumnDispersion& s = g.columns[c];
      nlohmann::json column = s;
      column["column"] = d.columns[c];
      column["fits"] = {FitJson(s.normal), FitJson(s.gumbel_max), FitJson(s.gumbel_min), FitJson(s.gev_max)};
      columns.push_back(std::move(column));
    }
    nlohmann::json limits = nlohmann::json::array();
    for (std::size_t l = 0; l < d.limits.size(); ++l) {
      const LimitExceedance& e = g.limits[l];
      nlohmann::json limit = e;
      limit["limit"] = d.limits[l].text;
      limit["wilson"] = {Number(e.wilson.lower), Number(e.wilson.upper)};
      limit["clopper_pearson"] = {Number(e.clopper_pearson.lower), Number(e.clopper_pearson.upper)};
      limits.push_back(std::move(limit));
    }
    groups.push_back(
        {{"label", g.label}, {"value", Number(g.value)}, {"columns", columns}, {"limits", limits}});
  }
  nlohmann::json j = d;
  j["percentiles"] = Numbers(d.options.percentiles);
  j["tail_probabilities"] = Numbers(d.options.tail_probabilities);
  j["confidence_level"] = d.options.confidence_level;
  j["groups"] = groups;
  if (written) j["written"] = "/" + DispersionGroupPath();
  return j;
}

void PrintTable(const Dispersion& d) {
  std::size_t w = 8;
  for (const auto& c : d.columns) w = std::max(w, c.size() + 2);
  std::cout << "# dispersion of " << d.archive
            << (d.study_name.empty() ? "" : " (study " + d.study_name + ")") << ": " << d.run_count
            << " runs, design " << (d.design_kind.empty() ? "?" : d.design_kind) << "\n";
  const std::string level = ShortNumber(100 * d.options.confidence_level) + " %";
  for (const auto& g : d.groups) {
    if (!d.group_by.empty()) std::cout << "\n## " << d.group_by << " = " << g.label << "\n";
    std::cout << std::left << std::setw(static_cast<int>(w)) << "column" << std::right << std::setw(7)
              << "values" << std::setw(7) << "failed" << std::setw(9) << "no value" << std::setw(8)
              << "pending" << std::setw(13) << "mean" << std::setw(13) << "std";
    for (double p : d.options.percentiles) {
      std::string label = "p";
      label += ShortNumber(p);
      std::cout << std::setw(12) << label;
    }
    std::cout << "\n";
    for (std::size_t c = 0; c < d.columns.size(); ++c) {
      const ColumnDispersion& s = g.columns[c];
      std::cout << std::left << std::setw(static_cast<int>(w)) << d.columns[c] << std::right << std::setw(7)
                << s.values << std::setw(7) << s.failed << std::setw(9) << s.without_value << std::setw(8)
                << s.pending << std::setw(13) << General(s.mean) << std::setw(13)
                << General(s.standard_deviation);
      for (double v : s.percentiles) std::cout << std::setw(12) << General(v);
      std::cout << "\n";
    }
    std::cout << "# tail fits: the value exceeded (upper) or not reached (lower) with probability";
    for (double p : d.options.tail_probabilities) std::cout << " " << ShortNumber(p);
    std::cout << "; A2 = Anderson-Darling, rejected at = smallest level of Stephens' table that rejects the "
                 "fit (none: not rejected at the largest)\n";
    std::cout << std::left << std::setw(static_cast<int>(w)) << "column" << std::setw(12) << "fit"
              << std::right << std::setw(13) << "location" << std::setw(13) << "scale" << std::setw(9) << "A2"
              << std::setw(12) << "rejected at";
    for (double p : d.options.tail_probabilities) std::cout << std::setw(12) << ShortNumber(p);
    std::cout << "\n";
    for (std::size_t c = 0; c < d.columns.size(); ++c) {
      const ColumnDispersion& s = g.columns[c];
      auto row = [&](const TailFit& fit, const std::string& name, const std::vector<double>& quantiles) {
        const double rejected = fit.goodness.rejected_at_percent();
        std::cout << std::left << std::setw(static_cast<int>(w)) << d.columns[c] << std::setw(12) << name
                  << std::right << std::setw(13) << General(fit.fit.location) << std::setw(13)
                  << General(fit.fit.scale) << std::setw(9) << General(fit.goodness.statistic)
                  << std::setw(12)
                  << (std::isnan(rejected) ? "-"
                      : rejected == 0      ? "none"
                                           : ShortNumber(rejected) + " %");
        for (double q : quantiles) std::cout << std::setw(12) << General(q);
        std::cout << "\n";
      };
      if (s.no_spread) {  // a stated result: nothing to fit
        std::cout << std::left << std::setw(static_cast<int>(w)) << d.columns[c] << "no spread: all "
                  << s.values << " values are " << General(s.minimum) << "; no tail law fitted\n";
        continue;
      }
      row(s.normal, "normal up", s.normal.upper_quantiles);
      row(s.normal, "normal low", s.normal.lower_quantiles);
      row(s.gumbel_max, "gumbel max", s.gumbel_max.upper_quantiles);
      row(s.gumbel_min, "gumbel min", s.gumbel_min.lower_quantiles);
      std::ostringstream gev_name;  // the shape in the name column: the table has no column for it
      gev_name << "gev xi=" << std::setprecision(2) << s.gev_max.shape;
      row(s.gev_max, gev_name.str(), s.gev_max.upper_quantiles);
    }
    if (!d.limits.empty()) {
      std::cout
          << "# limits: empirical probability with " << level
          << " intervals (failed runs and runs without a value are outside the sample, counted apart)\n";
      for (std::size_t l = 0; l < d.limits.size(); ++l) {
        const LimitExceedance& e = g.limits[l];
        std::cout << "  " << std::left << std::setw(static_cast<int>(w) + 8) << d.limits[l].text << std::right
                  << e.exceed << "/" << e.values << " = " << General(e.probability) << "  Wilson ["
                  << General(e.wilson.lower) << ", " << General(e.wilson.upper) << "]  Clopper-Pearson ["
                  << General(e.clopper_pearson.lower) << ", " << General(e.clopper_pearson.upper)
                  << "]  normal " << General(e.normal_probability) << "  gumbel "
                  << General(e.gumbel_probability) << "  gev " << General(e.gev_probability) << "  failed "
                  << e.failed << "\n";
      }
    }
  }
}

int RunDispersion(const DispersionFlags& flags) {
  if (flags.options.max_groups < 1) {
    throw InputError("command line", "--max-groups", std::to_string(flags.options.max_groups),
                     "expected >= 1");
  }
  if (risk::IsRiskArchive(flags.archive)) {
    // A subset simulation's archive (`gesweep risk`): its estimates, per limit of its [subset] table.
    if (!flags.options.limits.empty() || !flags.options.group_by.empty() || !flags.options.columns.empty()) {
      throw InputError("command line",
                       !flags.options.limits.empty()     ? "--limit"
                       : !flags.options.group_by.empty() ? "--group-by"
                                                         : "--columns",
                       "",
                       "none with a subset-simulation archive: its limits are its study's [subset] table");
    }
    return PrintRiskArchive(flags.archive, flags.format);
  }
  const FlagNames names = {{"columns", "--columns"},
                           {"limits", "--limit"},
                           {"group_by", "--group-by"},
                           {"percentiles", "--percentiles"},
                           {"tail_probabilities", "--tail-probabilities"},
                           {"confidence_level", "--confidence-level"}};
  return GuardArchive(names, [&] {
    ProductArchive archive = OpenProductArchive(flags.archive, flags.no_write, "dispersion");
    const ColumnCatalog catalog = ColumnCatalog::Of(archive.reader);
    const Dispersion result = ComputeDispersion(archive.reader, catalog, flags.options);
    archive.reader.Close();
    const bool written = archive.lock.has_value();
    if (written) WriteDispersionGroup(flags.archive, result, CommandLine(flags));
    if (flags.format == TableOrJson::kJson) {
      std::cout << ToJson(result, written).dump(2) << "\n";
    } else {
      PrintTable(result);
      if (written) std::cout << "# written to " << flags.archive << ": /" << DispersionGroupPath() << "\n";
    }
    return 0;
  });
}

void AddDispersionFlags(CLI::App& app, DispersionFlags& flags) {
  DispersionOptions& options = flags.options;
  AddArchiveArgument(app, flags.archive, "Archive of a sweep (typically a monte_carlo design)");
  app.add_option("--limit", options.limits,
                 "A limit COLUMN>VALUE or COLUMN<VALUE (repeatable), e.g. 'touchdown_sink_rate_mps>3': "
                 "the probability of exceeding it");
  app.add_option("--group-by", options.group_by,
                 "A column (e.g. a design parameter) whose values split the runs into groups");
}

const CommandRegistrar kRegistrar{CommandWith<DispersionFlags>(
    "dispersion",
    "Dispersion of a Monte Carlo sweep's results (by default the landing's touchdown columns): moments, "
    "percentiles, normal and Gumbel tail fits, limit exceedance probabilities with Wilson and "
    "Clopper-Pearson intervals, per group; writes /analysis/dispersion",
    AddDispersionFlags, RunDispersion)};

}  // namespace
}  // namespace gesweep::cli
