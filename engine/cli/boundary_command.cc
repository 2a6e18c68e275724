// gesweep boundary: H*(u0), the largest height at which the stability margin changes sign
// (docs/MODEL.md §6), by bracketing root finding on the continuous model. With --sensitivities, also
// the local sensitivities ∂H*/∂p of each boundary (docs/sensitivity.md), ranked.
#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "engine/analysis/local_sensitivity.h"
#include "engine/cli/command.h"
#include "engine/cli/json_util.h"
#include "engine/cli/model_flags.h"
#include "engine/common/errors.h"
#include "engine/modal/boundary.h"

namespace gesweep::cli {
namespace {

struct BoundaryFlags {
  ModelFlags model;
  double speed_mps = 0;
  std::string speeds;
  std::string format = "table";
  bool sensitivities = false;
};

std::string Scientific(double value, int digits = 4) {
  if (!std::isfinite(value)) return FormatNumber(value);
  std::ostringstream out;
  out << std::scientific << std::setprecision(digits - 1) << value;
  return out.str();
}

/// The "sensitivities" fields of one boundary object (docs/sensitivity.md, "gesweep boundary").
void AddSensitivitiesJson(const BoundarySensitivities& s, nlohmann::json& row) {
  nlohmann::json list = nlohmann::json::array();
  if (!s.valid) {
    row["sensitivities"] = list;
    row["sensitivities_reason"] = s.reason;
    return;
  }
  for (const auto& p : RankByRelativeEffect(s)) {
    list.push_back({{"parameter", p.parameter.Name()},
                    {"value", JsonNumber(p.value)},
                    {"value_unit", std::string(p.parameter.Unit())},
                    {"dH_dp", JsonNumber(p.height_derivative)},
                    {"dH_dp_unit", HeightDerivativeUnit(p.parameter)},
                    {"p_dH_dp_m", JsonNumber(p.relative_height_derivative_m)},
                    {"dsigma_dp_per_s", JsonNumber(p.margin_derivative)},
                    {"method", p.method == DerivativeMethod::kExact ? "exact" : "central_difference"}});
  }
  nlohmann::json no_effect = nlohmann::json::array();
  for (const auto& p : s.parameters) {
    if (!p.enters_state_matrix) no_effect.push_back(p.parameter.Name());
  }
  row["sensitivities"] = list;
  row["sensitivity_mode"] = s.mode;
  row["dsigma_dH_per_s_per_m"] = JsonNumber(s.margin_height_derivative_per_s_per_m);
  row["no_effect_parameters"] = no_effect;
}

/// The ranked table of one boundary's sensitivities.
void PrintSensitivitiesTable(const BoundarySensitivities& s) {
  std::cout << "\n# dH*/dp at u0 = " << FormatNumber(s.speed_mps, 6) << " m/s";
  if (!s.valid) {
    std::cout << ": none (" << s.reason << ")\n";
    return;
  }
  std::cout << ", H* = " << FormatNumber(s.height_m, 7) << " m: sigma set by the " << s.mode
            << " (dsigma/dH = " << Scientific(s.margin_height_derivative_per_s_per_m) << " 1/(s m)); ranked by |p dH*/dp|\n";
  std::cout << "  " << std::left << std::setw(22) << "parameter" << std::right << std::setw(12) << "value"
            << std::setw(14) << "dH*/dp" << "  " << std::left << std::setw(12) << "unit" << std::right
            << std::setw(14) << "p_dH*/dp_m" << std::setw(17) << "dsigma/dp_per_s" << "\n";
  for (const auto& p : RankByRelativeEffect(s)) {
    std::cout << "  " << std::left << std::setw(22) << p.parameter.Name() << std::right << std::setw(12)
              << FormatNumber(p.value, 6) << std::setw(14) << Scientific(p.height_derivative) << "  " << std::left
              << std::setw(12) << HeightDerivativeUnit(p.parameter) << std::right << std::setw(14)
              << Scientific(p.relative_height_derivative_m) << std::setw(17) << Scientific(p.margin_derivative)
              << (p.method == DerivativeMethod::kExact ? "" : "  (central difference)") << "\n";
  }
  std::string no_effect;
  for (const auto& p : s.parameters) {
    if (!p.enters_state_matrix) no_effect += " " + p.parameter.Name();
  }
  if (!no_effect.empty()) std::cout << "#   not in Eq. (1), no effect:" << no_effect << "\n";
}

int RunBoundary(const BoundaryFlags& flags) {
  if (flags.format != "table" && flags.format != "csv" && flags.format != "json") {
    throw InputError("command line", "--format", "'" + flags.format + "'", "expected table, csv or json");
  }
  if (flags.sensitivities && flags.format == "csv") {
    throw InputError("command line", "--format", "csv",
                     "expected table or json with --sensitivities (a second table does not fit one CSV stream)");
  }
  std::vector<double> speeds;
  if (!flags.speeds.empty()) {
    speeds = ParseRange(flags.speeds, "--speeds-mps");
    for (double v : speeds) RequirePositiveSpeed(v, "--speeds-mps");
  } else {
    RequirePositiveSpeed(flags.speed_mps, "--speed-mps");
    speeds.push_back(flags.speed_mps);
  }
  const LongitudinalModel model = flags.model.BuildModel();
  const double span = model.aircraft().wingspan_m;

  nlohmann::json boundaries = nlohmann::json::array();
  if (flags.format == "table") {
    std::cout << "# " << model.aircraft().name << ": stability boundary H* (unstable below, stable above), h-derivatives "
              << (model.options().h_derivatives ? "on" : "off") << ", cdh " << ToString(model.options().cdh) << ", "
              << ToString(model.options().interpolation) << " interpolation\n";
    std::cout << std::setw(12) << "speed_mps" << std::setw(12) << "H*_m" << std::setw(10) << "H*/b"
              << "  other crossings (m) / reason\n";
  } else if (flags.format == "csv") {
    std::cout << "speed_mps,height_m,height_over_span,other_crossings_m,reason\n";
  }
  std::vector<BoundarySensitivities> sensitivities;
  for (double speed : speeds) {
    const BoundaryResult result = FindBoundary(model, speed);
    if (flags.sensitivities) sensitivities.push_back(ComputeBoundarySensitivities(model, result));
    std::vector<double> others;
    for (const auto& crossing : result.crossings) {
      if (!result.height_m || crossing.height_m != *result.height_m) others.push_back(crossing.height_m);
    }
    if (flags.format == "json") {
      nlohmann::json row = {{"speed_mps", speed},
                            {"height_m", result.height_m ? nlohmann::json(*result.height_m) : nlohmann::json(nullptr)},
                            {"height_over_span",
                             result.height_m ? nlohmann::json(*result.height_m / span) : nlohmann::json(nullptr)},
                            {"other_crossings_m", others},
                            {"scanned_range_m", {result.lower_height_m, result.upper_height_m}}};
      if (!result.height_m) row["reason"] = result.reason;
      if (flags.sensitivities) AddSensitivitiesJson(sensitivities.back(), row);
      boundaries.push_back(row);
    } else {
      std::string other_text;
      for (double h : others) other_text += (other_text.empty() ? "" : " ") + FormatNumber(h, 6);
      const std::string h_text = result.height_m ? FormatNumber(*result.height_m, 7) : "none";
      const std::string ratio_text = result.height_m ? FormatNumber(*result.height_m / span, 5) : "none";
      if (flags.format == "csv") {
        std::cout << FormatNumber(speed) << "," << (result.height_m ? FormatNumber(*result.height_m) : "") << ","
                  << (result.height_m ? FormatNumber(*result.height_m / span) : "") << ",\"" << other_text
                  << "\",\"" << result.reason << "\"\n";
      } else {
        std::cout << std::setw(12) << FormatNumber(speed, 6) << std::setw(12) << h_text << std::setw(10)
                  << ratio_text << "  " << other_text << (other_text.empty() ? "" : " ") << result.reason << "\n";
      }
    }
  }
  if (flags.format == "json") std::cout << nlohmann::json{{"boundaries", boundaries}}.dump(2) << "\n";
  if (flags.format == "table") {
    for (const auto& s : sensitivities) PrintSensitivitiesTable(s);
  }
  return 0;
}

const CommandRegistrar kRegistrar{Command{
    "boundary", "Stability boundary H*(u0): where the largest real part of the eigenvalues changes sign",
    [](CLI::App& app) -> std::function<int()> {
      auto flags = std::make_shared<BoundaryFlags>();
      flags->model.AddTo(app);
      auto* speed = app.add_option("--speed-mps", flags->speed_mps, "Reference speed u0, m/s");
      auto* speeds = app.add_option("--speeds-mps", flags->speeds, "Speeds a:b:n (n evenly spaced) or a,b,c");
      speed->excludes(speeds);
      app.add_option("--format", flags->format, "table (default), csv or json");
      app.add_flag("--sensitivities", flags->sensitivities,
                   "Also print dH*/dp for every coefficient scale factor, CDo, mass, Iy and speed, ranked by "
                   "|p dH*/dp| (docs/sensitivity.md)");
      app.callback([speed, speeds] {
        if (speed->count() == 0 && speeds->count() == 0) {
          throw CLI::ValidationError("--speed-mps or --speeds-mps", "one of them is required");
        }
      });
      return [flags] { return RunBoundary(*flags); };
    }}};

}  // namespace
}  // namespace gesweep::cli
