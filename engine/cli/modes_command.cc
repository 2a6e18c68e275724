// gesweep modes: the eigen-analysis of Eq. (1) at a list of heights (docs/model.md §6).
#include <iomanip>
#include <iostream>

#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/json_util.h"
#include "engine/cli/model_flags.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/modal/modal_analysis.h"

namespace gesweep::cli {
namespace {

struct ModesFlags {
  ModelFlags model;
  ModesOptions options;  // its fields are flags (ModesOptions::Describe)
  DescribedFlags described;
  std::string heights;
  bool table_heights = false;
  std::string format = "table";
};

nlohmann::json ModeJson(const ModeProperties& mode) {
  return {{"re", mode.eigenvalue.real()},
          {"im", mode.eigenvalue.imag()},
          {"natural_frequency_radps", JsonNumber(mode.natural_frequency_radps)},
          {"damping_ratio", JsonNumber(mode.damping_ratio)},
          {"period_s", JsonNumber(mode.period_s)},
          {"time_to_half_or_double_s", JsonNumber(mode.time_to_half_or_double_s)},
          {"oscillatory", mode.oscillatory},
          {"neutral", mode.neutral}};
}

std::string ModeCell(const ModeProperties& mode) {
  if (mode.neutral) return "neutral";
  std::ostringstream out;
  out << std::fixed << std::setprecision(5) << mode.eigenvalue.real();
  if (mode.oscillatory) out << (mode.eigenvalue.imag() >= 0 ? "+" : "") << mode.eigenvalue.imag() << "i";
  return out.str();
}

// The heights of --heights-m (each within the limits table and above the wheel contact) or
// --table-heights (the aircraft's rows and free flight).
std::vector<double> Heights(const ModesFlags& flags, const Aircraft& aircraft) {
  std::vector<double> heights;
  if (flags.table_heights) {
    heights = aircraft.table_heights_m;
    heights.push_back(std::numeric_limits<double>::infinity());
  } else {
    heights = ParseNumberList(flags.heights, "--heights-m", /*allow_infinity=*/true);
  }
  for (double h : heights) {
    if (!std::isinf(h)) CheckInputLimit("height_m", h, "command line", "--heights-m");
    if (h < aircraft.wheel_contact_height_m) {
      throw InputError("command line", "--heights-m", FormatNumber(h),
                       "expected heights >= the wheel-contact height " +
                           FormatNumber(aircraft.wheel_contact_height_m) + " m of " + aircraft.source_path);
    }
  }
  return heights;
}

int RunModes(const ModesFlags& flags) {
  flags.described.Apply();
  const double speed_mps = flags.options.speed_mps;
  RequireFormat(flags.format, {"table", "csv", "json"});
  const LongitudinalModel model = flags.model.BuildModel();
  const Aircraft& aircraft = model.aircraft();
  const std::vector<double> heights = Heights(flags, aircraft);
  nlohmann::json rows = nlohmann::json::array();
  if (flags.format == "table") {
    std::cout << "# " << aircraft.name << " at u0 = " << speed_mps << " m/s, h-derivatives "
              << (model.options().h_derivatives ? "on" : "off") << ", cdh " << ToString(model.options().cdh)
              << ", " << ToString(model.options().interpolation) << " interpolation\n";
    std::cout << std::setw(9) << "H_m" << std::setw(8) << "H/b" << std::setw(24) << "short period λ"
              << std::setw(8) << "ζ_sp" << std::setw(22) << "phugoid λ" << std::setw(9) << "ζ_ph"
              << std::setw(13) << "height λ" << std::setw(12) << "σ_per_s"
              << "  stable\n";
  } else if (flags.format == "csv") {
    std::cout
        << "height_m,height_over_span,short_period_re,short_period_im,short_period_natural_frequency_radps,"
           "short_period_damping_ratio,phugoid_re,phugoid_im,phugoid_natural_frequency_radps,"
           "phugoid_damping_ratio,height_re,height_im,stability_margin_per_s,stable,classification\n";
  }
  for (double h : heights) {
    const ModalAnalysis modal = AnalyzeModes(model.StateMatrix(h, speed_mps));
    const double h_over_b = h / aircraft.wingspan_m;
    if (flags.format == "json") {
      nlohmann::json eigenvalues = nlohmann::json::array();
      for (const auto& z : modal.eigenvalues) eigenvalues.push_back({z.real(), z.imag()});
      rows.push_back({{"height_m", JsonHeight(h)},
                      {"height_over_span", std::isinf(h) ? nlohmann::json("inf") : nlohmann::json(h_over_b)},
                      {"eigenvalues", eigenvalues},
                      {"modes",
                       {{"short_period", ModeJson(modal.short_period)},
                        {"phugoid", ModeJson(modal.phugoid)},
                        {"height", ModeJson(modal.height)}}},
                      {"classification", std::string(ToString(modal.classification))},
                      {"stability_margin_per_s", JsonNumber(modal.stability_margin_per_s)},
                      {"stable", modal.stable}});
    } else if (flags.format == "csv") {
      const auto& sp = modal.short_period;
      const auto& ph = modal.phugoid;
      std::cout << FormatNumber(h) << "," << FormatNumber(h_over_b) << ","
                << FormatNumber(sp.eigenvalue.real()) << "," << FormatNumber(sp.eigenvalue.imag()) << ","
                << FormatNumber(sp.natural_frequency_radps) << "," << FormatNumber(sp.damping_ratio) << ","
                << FormatNumber(ph.eigenvalue.real()) << "," << FormatNumber(ph.eigenvalue.imag()) << ","
                << FormatNumber(ph.natural_frequency_radps) << "," << FormatNumber(ph.damping_ratio) << ","
                << FormatNumber(modal.height.eigenvalue.real()) << ","
                << FormatNumber(modal.height.eigenvalue.imag()) << ","
                << FormatNumber(modal.stability_margin_per_s) << "," << (modal.stable ? "true" : "false")
                << "," << ToString(modal.classification) << "\n";
    } else {
      std::ostringstream sigma;
      sigma << std::scientific << std::setprecision(3) << modal.stability_margin_per_s;
      std::cout << std::setw(9) << FormatNumber(h, 6) << std::setw(8) << FormatNumber(h_over_b, 3)
                << std::setw(22) << ModeCell(modal.short_period) << std::setw(8) << std::fixed
                << std::setprecision(4) << modal.short_period.damping_ratio << std::setw(22)
                << ModeCell(modal.phugoid) << std::setw(9) << modal.phugoid.damping_ratio << std::setw(13)
                << ModeCell(modal.height) << std::setw(12) << sigma.str() << "  "
                << (modal.stable ? "yes" : "NO") << "\n";
      std::cout.unsetf(std::ios::floatfield);
      if (modal.classification != ModeClassification::kStandard) {
        std::cout << "#   note: " << ToString(modal.classification) << " at H = " << FormatNumber(h)
                  << " m\n";
      }
    }
  }
  if (flags.format == "json")
    std::cout << nlohmann::json{{"speed_mps", speed_mps}, {"rows", rows}}.dump(2) << "\n";
  return 0;
}

void AddModesFlags(CLI::App& app, ModesFlags& flags) {
  flags.model.AddTo(app);
  flags.described.Add(app, flags.options, {"speed_mps"});
  auto* heights =
      app.add_option("--heights-m", flags.heights, "Comma-separated heights H, m (inf: free flight)");
  auto* table =
      app.add_flag("--table-heights", flags.table_heights, "The aircraft's table heights and free flight");
  heights->excludes(table);
  app.add_option("--format", flags.format, "table (default), csv or json");
  app.callback([heights, table] {
    if (heights->count() == 0 && table->count() == 0) {
      throw CLI::ValidationError("--heights-m or --table-heights", "one of them is required");
    }
  });
}

const CommandRegistrar kRegistrar{CommandWith<ModesFlags>(
    "modes", "Eigenvalues, modes and stability margin of Eq. (1) at a list of heights", AddModesFlags,
    RunModes)};

}  // namespace
}  // namespace gesweep::cli
