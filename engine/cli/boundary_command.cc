// gesweep boundary: H*(u0), the largest height at which the stability margin changes sign
// (docs/model.md §6), by bracketing root finding on the continuous model. With --sensitivities, also
// the local sensitivities ∂H*/∂p of each boundary (docs/sensitivity.md), ranked.
// With --archive, the boundary of a sweep's results instead: the sign change of the archived stability
// margin along height for each value of the other axes, refined on each run's model and written to
// /analysis/boundary (docs/report.md, "gesweep boundary --archive").
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include "engine/analyses/records.h"
#include "engine/archive/archive_error.h"
#include "engine/archive/archive_lock.h"
#include "engine/archive/archive_reader.h"
#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/json_util.h"
#include "engine/cli/model_flags.h"
#include "engine/cli/record_json.h"
#include "engine/common/errors.h"
#include "engine/estimators/boundary_curve.h"
#include "engine/estimators/local_sensitivity.h"
#include "engine/modal/boundary.h"
#include "engine/products/archive_boundary.h"
#include "engine/products/run_model.h"
#include "engine/query/run_columns.h"

namespace gesweep {
// The header of --archive's JSON, under the members' own names (PrintArchiveBoundary adds the rest).
GESWEEP_JSON_MEMBERS(ArchiveBoundary, archive, wingspan_m, tolerance_m, runs_used, runs_skipped, snapshot)
}  // namespace gesweep

namespace gesweep::cli {
namespace {

struct BoundaryFlags {
  ModelFlags model;
  double speed_mps = 0;
  std::string speeds;
  std::string format = "table";
  bool sensitivities = false;
  std::string archive;          // --archive: the boundary of a sweep's results
  std::vector<std::string> by;  // --by: order of the curve's axes
  bool no_write = false;        // --no-write: print only
  BoundaryOptions search;  // its fields are flags (BoundaryOptions::Describe): method, heights, tolerance
  DescribedFlags described;
};

// The search settings, checked against the aircraft in the flags' names (each flag's own range was
// checked as it was parsed).
BoundaryOptions SearchOptions(const BoundaryFlags& flags, const Aircraft& aircraft) {
  try {
    ValidateBoundaryOptions(flags.search, aircraft, "command line");
  } catch (const InputError& e) {
    flags.described.Rethrow(e);
  }
  return flags.search;
}

std::string CrossingText(const BoundaryCrossing& c) {
  std::string text = FormatNumber(c.height_m, 6);
  if (c.kind == CrossingKind::kHopf || c.kind == CrossingKind::kReal) {
    text += "(" + c.mode + (c.kind == CrossingKind::kHopf ? " pair" : " root") + ", " +
            (c.mode_stable_above ? "stable above" : "unstable above") + ")";
  } else if (c.kind == CrossingKind::kDiscontinuity) {
    text += "(table row: " + std::string(c.stable_above ? "stable above" : "unstable above") + ")";
  }
  return text;
}

std::string Scientific(double value, int digits = 4) {
  if (!std::isfinite(value)) return FormatNumber(value);
  std::ostringstream out;
  out << std::scientific << std::setprecision(digits - 1) << value;
  return out.str();
}

/// The ranked table of one boundary's sensitivities.
void PrintSensitivitiesTable(const BoundarySensitivities& s) {
  std::cout << "\n# dH*/dp at u0 = " << FormatNumber(s.speed_mps, 6) << " m/s";
  if (!s.valid) {
    std::cout << ": none (" << s.reason << ")\n";
    return;
  }
  std::cout << ", H* = " << FormatNumber(s.height_m, 7) << " m: sigma set by the " << s.mode
            << " (dsigma/dH = " << Scientific(s.margin_height_derivative_per_s_per_m)
            << " 1/(s m)); ranked by |p dH*/dp|\n";
  std::cout << "  " << std::left << std::setw(22) << "parameter" << std::right << std::setw(12) << "value"
            << std::setw(14) << "dH*/dp"
            << "  " << std::left << std::setw(12) << "unit" << std::right << std::setw(14) << "p_dH*/dp_m"
            << std::setw(17) << "dsigma/dp_per_s"
            << "\n";
  for (const auto& p : RankByRelativeEffect(s)) {
    std::cout << "  " << std::left << std::setw(22) << p.parameter.Name() << std::right << std::setw(12)
              << FormatNumber(p.value, 6) << std::setw(14) << Scientific(p.height_derivative) << "  "
              << std::left << std::setw(12) << HeightDerivativeUnit(p.parameter) << std::right
              << std::setw(14) << Scientific(p.relative_height_derivative_m) << std::setw(17)
              << Scientific(p.margin_derivative)
              << (p.method == DerivativeMethod::kExact ? "" : "  (central difference)") << "\n";
  }
  std::string no_effect;
  for (const auto& p : s.parameters) {
    if (!p.enters_state_matrix) no_effect += " " + p.parameter.Name();
  }
  if (!no_effect.empty()) std::cout << "#   not in Eq. (1), no effect:" << no_effect << "\n";
}

std::string KeyText(const ArchiveBoundary& boundary, std::size_t k, double value) {
  const auto& levels = boundary.key_levels[k];
  if (!levels.empty() && value >= 0 && value < static_cast<double>(levels.size()) &&
      value == std::floor(value)) {
    return levels[static_cast<std::size_t>(value)];
  }
  return FormatNumber(value, 8);
}

std::string CommandLine(const BoundaryFlags& flags) {
  std::string line = "gesweep boundary --archive " + flags.archive;
  if (!flags.by.empty()) {
    line += " --by ";
    for (std::size_t i = 0; i < flags.by.size(); ++i) line += (i ? "," : "") + flags.by[i];
  }
  if (flags.sensitivities) line += " --sensitivities";
  if (flags.format != "table") line += " --format " + flags.format;
  return line;
}

// The value, or NaN when there is none.
double NanOr(const std::optional<double>& v) { return v ? *v : std::nan(""); }

// The boundary as JSON: the product's fields, and one object per boundary point (with its
// sensitivities when computed).
void PrintArchiveBoundaryJson(const ArchiveBoundary& boundary,
                              const std::vector<std::optional<BoundarySensitivities>>& sensitivities,
                              bool written) {
  nlohmann::json points = nlohmann::json::array();
  for (std::size_t i = 0; i < boundary.points.size(); ++i) {
    const ArchiveBoundaryPoint& p = boundary.points[i];
    nlohmann::json row;
    for (std::size_t k = 0; k < boundary.key_names.size(); ++k) {
      row[boundary.key_names[k]] = boundary.key_levels[k].empty()
                                       ? JsonNumber(p.key_values[k])
                                       : nlohmann::json(KeyText(boundary, k, p.key_values[k]));
    }
    row["height_m"] = JsonNumber(NanOr(p.height_m));
    row["height_over_span"] = JsonNumber(NanOr(p.height_over_span));
    row["grid_bracket_m"] = {JsonNumber(p.grid_lower_height_m), JsonNumber(p.grid_upper_height_m)};
    row["bracket_width_m"] = JsonNumber(p.bracket_width_m);
    row["grid_crossings"] = p.grid_crossings;
    row["heights"] = p.heights;
    if (!p.reason.empty()) row["reason"] = p.reason;
    if (sensitivities[i]) {
      JsonRecordSink<nlohmann::json> sink{&row};
      SensitivitiesRecord(*sensitivities[i], sink);
    }
    points.push_back(row);
  }
  nlohmann::json out = boundary;
  out["study"] = boundary.study_name;
  out["aircraft"] = boundary.aircraft_name;
  out["keys"] = boundary.key_names;
  out["written"] = written;
  out["boundaries"] = points;
  std::cout << out.dump(2) << "\n";
}

// The boundary as CSV: one row per boundary point (empty cells for NaN).
void PrintArchiveBoundaryCsv(const ArchiveBoundary& boundary) {
  for (const auto& name : boundary.key_names) std::cout << name << ",";
  std::cout
      << "height_m,height_over_span,grid_lower_height_m,grid_upper_height_m,bracket_width_m,grid_crossings,"
         "heights,reason\n";
  for (const auto& p : boundary.points) {
    for (std::size_t k = 0; k < boundary.key_names.size(); ++k)
      std::cout << KeyText(boundary, k, p.key_values[k]) << ",";
    auto number = [](double v) { return std::isnan(v) ? std::string() : FormatNumber(v); };
    std::cout << number(NanOr(p.height_m)) << "," << number(NanOr(p.height_over_span)) << ","
              << number(p.grid_lower_height_m) << "," << number(p.grid_upper_height_m) << ","
              << number(p.bracket_width_m) << "," << p.grid_crossings << "," << p.heights << ",\"" << p.reason
              << "\"\n";
  }
}

// The boundary as a table: a heading, one line per boundary point, the run counts, then each
// point's sensitivities.
void PrintArchiveBoundaryTable(const ArchiveBoundary& boundary,
                               const std::vector<std::optional<BoundarySensitivities>>& sensitivities,
                               bool written) {
  std::cout << "# " << boundary.aircraft_name
            << ": stability boundary H* (unstable below, stable above) from "
            << "results/modes/stability_margin_per_s of " << boundary.archive << " (study "
            << boundary.study_name
            << "): the grid's sign change along height_m, refined on each run's model to "
            << FormatNumber(boundary.tolerance_m * 1000.0, 3) << " mm\n";
  std::vector<int> widths;
  for (const auto& name : boundary.key_names) {
    widths.push_back(std::max(12, static_cast<int>(name.size()) + 2));
    std::cout << std::setw(widths.back()) << name;
  }
  std::cout << std::setw(12) << "H*_m" << std::setw(10) << "H*/b" << std::setw(24) << "grid bracket (m)"
            << "  note\n";
  for (const auto& p : boundary.points) {
    for (std::size_t k = 0; k < boundary.key_names.size(); ++k) {
      std::cout << std::setw(widths[k]) << KeyText(boundary, k, p.key_values[k]);
    }
    const std::string bracket =
        std::isnan(p.grid_lower_height_m)
            ? std::string()
            : FormatNumber(p.grid_lower_height_m, 6) + " - " + FormatNumber(p.grid_upper_height_m, 6);
    std::cout << std::setw(12) << (p.height_m ? FormatNumber(*p.height_m, 7) : "none") << std::setw(10)
              << (p.height_over_span ? FormatNumber(*p.height_over_span, 5) : "none") << std::setw(24)
              << bracket << "  " << p.reason;
    if (p.height_m && p.grid_crossings > 1)
      std::cout << "(" << p.grid_crossings << " sign changes on the grid)";
    std::cout << "\n";
  }
  std::cout << "# " << boundary.runs_used << " runs used, " << boundary.runs_skipped
            << " skipped (failed, pending or without a finite sigma)"
            << (boundary.snapshot ? "; snapshot of an archive a sweep is writing" : "")
            << (written ? "; written to " + boundary.archive + ":/" + kBoundaryGroup : "") << "\n";
  for (const auto& s : sensitivities) {
    if (s) PrintSensitivitiesTable(*s);
  }
}

void PrintArchiveBoundary(const ArchiveBoundary& boundary, const BoundaryFlags& flags,
                          const std::vector<std::optional<BoundarySensitivities>>& sensitivities,
                          bool written) {
  if (flags.format == "json") {
    PrintArchiveBoundaryJson(boundary, sensitivities, written);
  } else if (flags.format == "csv") {
    PrintArchiveBoundaryCsv(boundary);
  } else {
    PrintArchiveBoundaryTable(boundary, sensitivities, written);
  }
}

nlohmann::json CurveJson(const BoundaryCurve& curve) {
  nlohmann::json points = nlohmann::json::array(), events = nlohmann::json::array();
  for (const auto& p : curve.points) {
    points.push_back({{"speed_mps", p.speed_mps},
                      {"height_m", p.height_m},
                      {"height_over_span", p.height_over_span},
                      {"dH_du_m_per_mps", JsonNumber(p.height_speed_derivative)},
                      {"kind", std::string(ToString(p.kind))},
                      {"mode", p.mode},
                      {"certified", p.certified},
                      {"branch", p.branch}});
  }
  for (const auto& e : curve.events) {
    events.push_back({{"speed_mps", e.speed_mps},
                      {"what", e.what},
                      {"height_below_m", JsonNumber(e.height_below_m)},
                      {"height_above_m", JsonNumber(e.height_above_m)},
                      {"reason", e.reason}});
  }
  return {{"speed_range_mps", {curve.lower_speed_mps, curve.upper_speed_mps}},
          {"points", points},
          {"events", events},
          {"accepted_steps", curve.accepted_steps},
          {"rejected_steps", curve.rejected_steps},
          {"finder_calls", curve.finder_calls}};
}

void PrintCurveSummary(const BoundaryCurve& curve) {
  std::cout << "# curve traced from " << FormatNumber(curve.lower_speed_mps, 6) << " to "
            << FormatNumber(curve.upper_speed_mps, 6)
            << " m/s by continuation on the crossing criterion: " << curve.points.size() << " points, "
            << curve.rejected_steps << " steps rejected, " << curve.finder_calls << " certified checks\n";
  for (const auto& e : curve.events) {
    std::cout << "#   at " << FormatNumber(e.speed_mps, 7) << " m/s the boundary " << e.what;
    if (e.what == "appears")
      std::cout << " at H* = " << FormatNumber(e.height_above_m, 6) << " m (below: " << e.reason << ")";
    if (e.what == "ends")
      std::cout << " at H* = " << FormatNumber(e.height_below_m, 6) << " m (above: " << e.reason << ")";
    if (e.what == "jumps")
      std::cout << " from " << FormatNumber(e.height_below_m, 6) << " to "
                << FormatNumber(e.height_above_m, 6) << " m";
    std::cout << "\n";
  }
}

// The flags are checked (RunBoundary).
int RunArchiveBoundary(const BoundaryFlags& flags) {
  return GuardArchive([&] {
    // Claim the archive before reading it, so no sweep starts writing it meanwhile; refused while
    // one writes it.
    std::optional<ArchiveLock> lock;
    if (!flags.no_write) {
      lock.emplace(ArchiveLock::Acquire(flags.archive,
                                        "run gesweep boundary --archive once the sweep has finished, or pass "
                                        "--no-write to print the boundary of the runs complete so far"));
    }
    ArchiveReader archive = ArchiveReader::Open(flags.archive);
    if (!flags.no_write && archive.snapshot()) {
      throw InputError(
          flags.archive, "", "",
          "the sweep that wrote this archive stopped without closing it (killed?); finish it with "
          "gesweep run STUDY -o " +
              flags.archive + " --resume, or pass --no-write");
    }
    const ColumnCatalog catalog = ColumnCatalog::Of(archive);
    ArchiveRunModels models = ArchiveRunModels::Of(archive);
    BoundaryExtractionOptions options;
    options.by = flags.by;
    const ArchiveBoundary boundary = ExtractBoundary(archive, catalog, models, options);
    archive.Close();
    std::vector<std::optional<BoundarySensitivities>> sensitivities(boundary.points.size());
    if (flags.sensitivities) {
      for (std::size_t i = 0; i < boundary.points.size(); ++i) {
        const ArchiveBoundaryPoint& p = boundary.points[i];
        if (p.height_m)
          sensitivities[i] = ComputeBoundarySensitivities(models.Model(p.parameters), p.refined);
      }
    }
    // With speed the only other axis, the curve H*(u0) traced on the continuous model over the
    // archive's speeds, beside the per-point boundary (the report draws it on the stability map).
    std::optional<BoundaryCurve> curve;
    if (boundary.key_names == std::vector<std::string>{"speed_mps"} && boundary.points.size() >= 2) {
      const double lower = boundary.points.front().key_values[0],
                   upper = boundary.points.back().key_values[0];
      if (upper > lower && lower > 0) {
        curve = TraceBoundary(models.Model(boundary.points.front().parameters), lower, upper);
      }
    }
    if (!flags.no_write) {
      WriteBoundaryGroup(flags.archive, boundary, CommandLine(flags));
      if (curve) {
        BoundaryCurveRecord record;
        record.wingspan_m = boundary.wingspan_m;
        for (const auto& p : curve->points) {
          record.speed_mps.push_back(p.speed_mps);
          record.height_m.push_back(p.height_m);
          record.height_over_span.push_back(p.height_over_span);
          record.height_speed_derivative.push_back(p.height_speed_derivative);
          record.branch.push_back(p.branch);
        }
        for (const auto& e : curve->events) {
          record.event_speed_mps.push_back(e.speed_mps);
          record.event_what.push_back(e.what);
        }
        WriteBoundaryCurveGroup(flags.archive, record, CommandLine(flags));
      }
    }
    PrintArchiveBoundary(boundary, flags, sensitivities, !flags.no_write);
    if (curve && flags.format == "table") {
      PrintCurveSummary(*curve);
      if (!flags.no_write)
        std::cout << "# curve written to " << flags.archive << ":/" << kBoundaryCurveGroup << "\n";
    }
    return 0;
  });
}

// The speeds to print and, for a:b and a:b:n, the curve H*(u0) traced over them.
struct SpeedPlan {
  std::vector<double> speeds;
  std::optional<BoundaryCurve> curve;
};

SpeedPlan PlanSpeeds(const BoundaryFlags& flags, const LongitudinalModel& model,
                     const BoundaryOptions& search) {
  SpeedPlan plan;
  const auto colons = std::count(flags.speeds.begin(), flags.speeds.end(), ':');
  if (!flags.speeds.empty() && colons == 1) {
    // a:b: the traced curve, printed at its own points.
    const std::string a = flags.speeds.substr(0, flags.speeds.find(':'));
    const std::string b = flags.speeds.substr(flags.speeds.find(':') + 1);
    const std::vector<double> ends = ParseNumberList(a + "," + b, "--speeds-mps", false);
    const double lower = ends[0], upper = ends[1];
    RequireWithinLimit(ends, "speed_mps", "--speeds-mps");
    if (!(upper > lower))
      throw InputError("command line", "--speeds-mps", "'" + flags.speeds + "'", "expected a:b with a < b");
    BoundaryCurveOptions options;
    options.search = search;
    plan.curve = TraceBoundary(model, lower, upper, options);
    for (const auto& p : plan.curve->points) plan.speeds.push_back(p.speed_mps);
  } else if (!flags.speeds.empty()) {
    plan.speeds = ParseRange(flags.speeds, "--speeds-mps");
    RequireWithinLimit(plan.speeds, "speed_mps", "--speeds-mps");
    if (colons == 2 && plan.speeds.size() > 1 && plan.speeds.back() > plan.speeds.front()) {
      // a:b:n: the curve traced over [a, b], printed at the n speeds.
      BoundaryCurveOptions options;
      options.search = search;
      plan.curve = TraceBoundary(model, plan.speeds.front(), plan.speeds.back(), options);
    }
  } else {
    plan.speeds.push_back(flags.speed_mps);
  }
  return plan;
}

int RunBoundary(const BoundaryFlags& flags) {
  flags.described.Apply();
  RequireFormat(flags.format, {"table", "csv", "json"});
  if (flags.sensitivities && flags.format == "csv") {
    throw InputError(
        "command line", "--format", "csv",
        "expected table or json with --sensitivities (a second table does not fit one CSV stream)");
  }
  if (!flags.archive.empty()) return RunArchiveBoundary(flags);
  const LongitudinalModel model = flags.model.BuildModel();
  const BoundaryOptions search = SearchOptions(flags, model.aircraft());  // before anything is printed
  const auto [speeds, curve] = PlanSpeeds(flags, model, search);
  const double span = model.aircraft().wingspan_m;

  nlohmann::json boundaries = nlohmann::json::array();
  if (flags.format == "table") {
    std::cout << "# " << model.aircraft().name
              << ": stability boundary H* (unstable below, stable above), h-derivatives "
              << (model.options().h_derivatives ? "on" : "off") << ", cdh " << ToString(model.options().cdh)
              << ", " << ToString(model.options().interpolation) << " interpolation\n";
    std::cout << std::setw(12) << "speed_mps" << std::setw(12) << "H*_m" << std::setw(10) << "H*/b"
              << "  other crossings (m) / reason\n";
  } else if (flags.format == "csv") {
    std::cout << "speed_mps,height_m,height_over_span,other_crossings_m,reason\n";
  }
  std::vector<BoundarySensitivities> sensitivities;
  for (double speed : speeds) {
    BoundaryResult result = FindBoundary(model, speed, search);
    if (curve && result.height_m) {
      // The printed H* is the curve's (Newton on the criterion from the traced points); the finder,
      // run here for the other crossings, gives the same root to rounding.
      if (const auto on_curve = BoundaryOnCurve(model, *curve, speed)) {
        if (std::abs(*on_curve - *result.height_m) <= 1e-6) result.height_m = *on_curve;
      }
    }
    if (flags.sensitivities) sensitivities.push_back(ComputeBoundarySensitivities(model, result));
    std::vector<double> others;
    std::string other_text;
    for (const auto& crossing : result.crossings) {
      if (!result.height_m || std::abs(crossing.height_m - *result.height_m) > 1e-9) {
        others.push_back(crossing.height_m);
        other_text += (other_text.empty() ? "" : " ") + CrossingText(crossing);
      }
    }
    if (flags.format == "json") {
      const std::optional<BoundarySensitivities> asked =
          flags.sensitivities ? std::optional(sensitivities.back()) : std::nullopt;
      boundaries.push_back(
          RecordJson<nlohmann::json>([&](auto& sink) { BoundaryRecord(speed, result, span, asked, sink); }));
    } else {
      const std::string h_text = result.height_m ? FormatNumber(*result.height_m, 7) : "none";
      const std::string ratio_text = result.height_m ? FormatNumber(*result.height_m / span, 5) : "none";
      if (flags.format == "csv") {
        std::string numbers;
        for (double h : others) numbers += (numbers.empty() ? "" : " ") + FormatNumber(h, 6);
        std::cout << FormatNumber(speed) << "," << (result.height_m ? FormatNumber(*result.height_m) : "")
                  << "," << (result.height_m ? FormatNumber(*result.height_m / span) : "") << ",\"" << numbers
                  << "\",\"" << result.reason << "\"\n";
      } else {
        std::cout << std::setw(12) << FormatNumber(speed, 6) << std::setw(12) << h_text << std::setw(10)
                  << ratio_text << "  " << other_text << (other_text.empty() ? "" : " ") << result.reason
                  << "\n";
      }
    }
  }
  if (flags.format == "json") {
    nlohmann::json out{{"boundaries", boundaries}};
    if (curve) out["curve"] = CurveJson(*curve);
    std::cout << out.dump(2) << "\n";
  }
  if (flags.format == "table") {
    if (curve) PrintCurveSummary(*curve);
    for (const auto& s : sensitivities) PrintSensitivitiesTable(s);
  }
  return 0;
}

void AddBoundaryFlags(CLI::App& app, BoundaryFlags& flags) {
  flags.model.AddTo(app, /*aircraft_required=*/false);
  auto* speed = AddLimitedOption(app, "--speed-mps", flags.speed_mps, "speed_mps", "Reference speed u0, m/s");
  auto* speeds =
      app.add_option("--speeds-mps", flags.speeds,
                     "Speeds a:b (the curve H*(u0) traced by continuation, printed at its points), "
                     "a:b:n (traced, printed at n evenly spaced speeds) or a,b,c (each on its own)");
  speed->excludes(speeds);
  auto* archive =
      app.add_option("--archive", flags.archive,
                     "Instead of --aircraft: the boundary of a sweep's archive (results/modes over a "
                     "height_m axis), refined on each run's model, written to /analysis/boundary");
  archive->excludes(app.get_option("--aircraft"))->excludes(speed)->excludes(speeds);
  auto* by = app.add_option("--by", flags.by,
                            "With --archive: the swept parameters to order the curve by, e.g. speed_mps "
                            "(default: the design's order)")
                 ->delimiter(',');
  auto* no_write = app.add_flag("--no-write", flags.no_write, "With --archive: print only, write nothing");
  app.add_option("--format", flags.format, "table (default), csv or json");
  flags.described.Add(app, flags.search);
  app.add_flag("--sensitivities", flags.sensitivities,
               "Also print dH*/dp for every coefficient scale factor, CDo, mass, Iy and speed, ranked by "
               "|p dH*/dp| (docs/sensitivity.md)");
  app.callback([&app, speed, speeds, archive, by, no_write] {
    if (archive->count() > 0) {
      for (const char* model_flag : {"--cdh", "--no-h-derivatives", "--interpolation"}) {
        if (app.get_option(model_flag)->count() > 0) {
          throw CLI::ValidationError(model_flag,
                                     "the model of --archive comes from the archive's runs; "
                                     "sweep the model options in the study instead");
        }
      }
      for (const char* search_flag : {"--lower-height-m", "--upper-height-m", "--tolerance-m"}) {
        if (app.get_option(search_flag)->count() > 0) {
          throw CLI::ValidationError(search_flag,
                                     "sets the search on --aircraft's model; --archive refines each "
                                     "run's boundary within the archive's own height grid");
        }
      }
      return;
    }
    if (by->count() > 0 || no_write->count() > 0) {
      throw CLI::ValidationError(by->count() > 0 ? "--by" : "--no-write", "only with --archive");
    }
    if (app.get_option("--aircraft")->count() == 0) {
      throw CLI::ValidationError("--aircraft or --archive", "one of them is required");
    }
    if (speed->count() == 0 && speeds->count() == 0) {
      throw CLI::ValidationError("--speed-mps or --speeds-mps", "one of them is required");
    }
  });
}

const CommandRegistrar kRegistrar{CommandWith<BoundaryFlags>(
    "boundary", "Stability boundary H*(u0): where the largest real part of the eigenvalues changes sign",
    AddBoundaryFlags, RunBoundary)};

}  // namespace
}  // namespace gesweep::cli
