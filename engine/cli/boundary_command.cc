// gesweep boundary: H*(u0), the largest height at which the stability margin changes sign
// (docs/MODEL.md §6), by bracketing root finding on the continuous model.
#include <iomanip>
#include <iostream>

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
};

int RunBoundary(const BoundaryFlags& flags) {
  if (flags.format != "table" && flags.format != "csv" && flags.format != "json") {
    throw InputError("command line", "--format", "'" + flags.format + "'", "expected table, csv or json");
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
  for (double speed : speeds) {
    const BoundaryResult result = FindBoundary(model, speed);
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
      app.callback([speed, speeds] {
        if (speed->count() == 0 && speeds->count() == 0) {
          throw CLI::ValidationError("--speed-mps or --speeds-mps", "one of them is required");
        }
      });
      return [flags] { return RunBoundary(*flags); };
    }}};

}  // namespace
}  // namespace gesweep::cli
