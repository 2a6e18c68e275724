#include "engine/sweep/parameter_catalog.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "engine/aircraft/coefficient.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

// Heights above this are outside the ISA troposphere the model's density uses (MODEL.md §1).
constexpr double kMaximumHeight_m = 11000.0;
// A generous subsonic bound: the model is incompressible (CDu = CLu = CMu = 0, MODEL.md §2).
constexpr double kMaximumSpeed_mps = 300.0;

ParameterInfo Real(std::string name, std::string units, std::string description, ParameterGroup group,
                   std::optional<double> default_value) {
  ParameterInfo info;
  info.name = std::move(name);
  info.units = std::move(units);
  info.description = std::move(description);
  info.kind = ParameterKind::kReal;
  info.group = group;
  info.default_value = default_value;
  return info;
}

ParameterInfo Positive(ParameterInfo info) {
  info.minimum = 0.0;
  info.minimum_exclusive = true;
  return info;
}

ParameterInfo Range(ParameterInfo info, double minimum, double maximum) {
  info.minimum = minimum;
  info.maximum = maximum;
  return info;
}

std::vector<ParameterInfo> BuildCatalog() {
  std::vector<ParameterInfo> c;
  using G = ParameterGroup;

  // The flight condition.
  {
    ParameterInfo height =
        Real("height_m", "m",
             "Height H of the mean aerodynamic chord above ground: the evaluation height (modes), "
             "the start height (open_loop, landing)",
             G::kFlight, std::nullopt);
    height.minimum = 0.0;
    height.minimum_exclusive = true;
    height.maximum = kMaximumHeight_m;
    c.push_back(height);
    ParameterInfo speed =
        Positive(Real("speed_mps", "m/s", "Reference forward speed u0", G::kFlight, std::nullopt));
    speed.maximum = kMaximumSpeed_mps;
    c.push_back(speed);
  }

  // Model switches (docs/MODEL.md §2-§4).
  {
    ParameterInfo h =
        Real("h_derivatives", "1", "Whether Xh, Zh and Mh are in the model (MODEL.md §4)", G::kModel, 1.0);
    h.kind = ParameterKind::kBoolean;
    h.levels = {"false", "true"};
    c.push_back(h);
    ParameterInfo cdh =
        Real("cdh", "1", "How CDh is obtained: polar = d(k CLo^2)/dh, zero (MODEL.md §3)", G::kModel, 0.0);
    cdh.kind = ParameterKind::kChoice;
    cdh.levels = {"polar", "zero"};
    c.push_back(cdh);
    ParameterInfo interpolation = Real(
        "interpolation", "1", "Table interpolation in height: linear or pchip (MODEL.md §2)", G::kModel, 0.0);
    interpolation.kind = ParameterKind::kChoice;
    interpolation.levels = {"linear", "pchip"};
    c.push_back(interpolation);
  }

  // Multiplicative scale factors on every coefficient column and on CDo.
  for (std::string_view name : kCoefficientNames) {
    c.push_back(Real("scale." + std::string(name), "1",
                     "Multiplicative factor on the coefficient " + std::string(name) + " at every height",
                     G::kModel, 1.0));
  }
  c.push_back(
      Real("scale.CDo", "1", "Multiplicative factor on the parasite drag coefficient CDo", G::kModel, 1.0));

  // Mass properties; the defaults are the aircraft's (DefaultValue).
  c.push_back(Positive(
      Real("mass_kg", "kg", "Airplane mass m (default: the aircraft file's)", G::kModel, std::nullopt)));
  c.push_back(Positive(Real("pitch_inertia_kgm2", "kg m^2",
                            "Pitching moment of inertia Iy (default: the aircraft file's)", G::kModel,
                            std::nullopt)));
  c.push_back(
      Range(Real("cg_shift_over_chord", "1",
                 "CG moved aft by this fraction of the mean chord (negative: forward)", G::kModel, 0.0),
            -1.0, 1.0));

  // Open-loop perturbation (MODEL.md §7).
  c.push_back(
      Range(Real("pulse_amplitude_deg", "deg",
                 "Elevator pulse amplitude, positive trailing edge down (paper: 5 deg)", G::kOpenLoop, 5.0),
            -30.0, 30.0));
  c.push_back(Range(
      Real("pulse_duration_s", "s", "Elevator pulse duration (paper: 0.2 s)", G::kOpenLoop, 0.2), 0.0, 1e4));

  // Landing controller (MODEL.md §8; engine/control/landing_config.h, docs/landing.md). A NaN
  // default means "automatic": the controller's own rule.
  {
    ParameterInfo gamma =
        Real("glide_slope_deg", "deg",
             "Glide-slope angle gamma, positive for a descent (the paper: 2.5 to 3 deg)", G::kLanding, 2.5);
    gamma.minimum = 0.0;
    gamma.minimum_exclusive = true;
    gamma.maximum = 10.0;
    c.push_back(gamma);
    c.push_back(
        Positive(Real("flare_height_m", "m", "Height Ho at which the flare starts", G::kLanding, 10.0)));
    c.push_back(Positive(Real("flare_tau_s", "s",
                              "Time constant tau of the exponential flare command (default NaN: automatic, "
                              "Ho/(u0 sin gamma), so the commanded sink rate is continuous at Ho)",
                              G::kLanding, std::numeric_limits<double>::quiet_NaN())));
    const char* states[] = {"delta_u",  "delta_w",   "pitch_rate",  "delta_theta",   "delta_h",
                            "elevator", "deviation", "compensator", "error_integral"};
    for (const char* state : states) {
      ParameterInfo q = Real(std::string("lqr.q_") + state, "1",
                             std::string("LQR weight on the state ") + state +
                                 " of the paper's Eq. (14) (diagonal of Q; the paper: identity)",
                             G::kLanding, 1.0);
      q.minimum = 0.0;
      c.push_back(q);
    }
    c.push_back(Positive(
        Real("lqr.r", "1", "LQR weight R on the elevator command (the paper: 1)", G::kLanding, 1.0)));
  }

  // Inputs of the verification models (Ishigami, linear): dimensionless, no default meaning.
  for (int i = 1; i <= 8; ++i) {
    std::string name = "x";
    name += std::to_string(i);
    c.push_back(Real(name, "1", "Input " + name + " of the verification models", G::kVerification, 0.0));
  }
  return c;
}

std::string FormatNumber(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

}  // namespace

const std::vector<ParameterInfo>& ParameterCatalog() {
  static const std::vector<ParameterInfo> catalog = BuildCatalog();
  return catalog;
}

int ParameterCount() { return static_cast<int>(ParameterCatalog().size()); }

std::optional<ParameterId> FindParameter(std::string_view name) {
  const auto& catalog = ParameterCatalog();
  for (std::size_t i = 0; i < catalog.size(); ++i) {
    if (catalog[i].name == name) return static_cast<ParameterId>(i);
  }
  return std::nullopt;
}

ParameterId RequireParameter(std::string_view name) {
  const auto id = FindParameter(name);
  GESWEEP_DEMAND(id.has_value());
  return *id;
}

std::vector<std::string> ParameterNames() {
  std::vector<std::string> names;
  for (const auto& info : ParameterCatalog()) names.push_back(info.name);
  return names;
}

std::optional<double> DefaultValue(ParameterId id, const Aircraft* aircraft) {
  const ParameterInfo& info = ParameterCatalog().at(id);
  if (aircraft != nullptr) {
    if (info.name == "mass_kg") return aircraft->mass_kg;
    if (info.name == "pitch_inertia_kgm2") return aircraft->pitch_inertia_kgm2;
  }
  return info.default_value;
}

std::string DescribeAllowedValues(ParameterId id) {
  const ParameterInfo& info = ParameterCatalog().at(id);
  if (info.kind != ParameterKind::kReal) {
    std::string text = "one of ";
    for (std::size_t i = 0; i < info.levels.size(); ++i) {
      text += (i ? ", " : "") + info.levels[i];
    }
    return text;
  }
  std::string text = "a number";
  const bool has_min = info.minimum > -1e299;
  const bool has_max = info.maximum < 1e299;
  if (has_min && has_max) {
    text += std::string(" in ") + (info.minimum_exclusive ? "(" : "[") + FormatNumber(info.minimum) + ", " +
            FormatNumber(info.maximum) + (info.maximum_exclusive ? ")" : "]");
  } else if (has_min) {
    text += std::string(info.minimum_exclusive ? " > " : " >= ") + FormatNumber(info.minimum);
  } else if (has_max) {
    text += std::string(info.maximum_exclusive ? " < " : " <= ") + FormatNumber(info.maximum);
  }
  if (info.units != "1") text += " (" + info.units + ")";
  return text;
}

std::string CheckParameterValue(ParameterId id, double value, const Aircraft* aircraft) {
  const ParameterInfo& info = ParameterCatalog().at(id);
  if (!std::isfinite(value)) return "expected " + DescribeAllowedValues(id);
  if (info.kind != ParameterKind::kReal) {
    const bool is_level =
        value >= 0 && value < static_cast<double>(info.levels.size()) && value == std::floor(value);
    return is_level ? "" : "expected " + DescribeAllowedValues(id);
  }
  const bool below = info.minimum_exclusive ? !(value > info.minimum) : !(value >= info.minimum);
  const bool above = info.maximum_exclusive ? !(value < info.maximum) : !(value <= info.maximum);
  if (below || above) return "expected " + DescribeAllowedValues(id);
  if (aircraft != nullptr && info.name == "height_m") {
    if (value < aircraft->wheel_contact_height_m) {
      return "expected a height >= the wheel-contact height " +
             FormatNumber(aircraft->wheel_contact_height_m) + " m of " + aircraft->source_path;
    }
    if (aircraft->field_elevation_m + value > kMaximumHeight_m) {
      return "expected field elevation + height <= " + FormatNumber(kMaximumHeight_m) +
             " m (the ISA troposphere the density model uses)";
    }
  }
  return "";
}

std::string FormatParameterValue(ParameterId id, double value) {
  const ParameterInfo& info = ParameterCatalog().at(id);
  if (info.kind != ParameterKind::kReal && value >= 0 && value < static_cast<double>(info.levels.size()) &&
      value == std::floor(value)) {
    return info.levels[static_cast<std::size_t>(value)];
  }
  return FormatNumber(value);
}

std::optional<double> ParseParameterLevel(ParameterId id, std::string_view text) {
  const ParameterInfo& info = ParameterCatalog().at(id);
  for (std::size_t i = 0; i < info.levels.size(); ++i) {
    if (info.levels[i] == text) return static_cast<double>(i);
  }
  return std::nullopt;
}

}  // namespace gesweep
