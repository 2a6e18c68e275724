#include "engine/analyses/parameter_catalog.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/aircraft/coefficient.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/disturbance/disturbance_options.h"
#include "engine/dynamics/model_options.h"

namespace gesweep {
namespace {

// A real parameter whose range is the limits table's entry `limit`.
ParameterInfo Real(std::string name, std::string units, std::string description, ParameterGroup group,
                   std::optional<double> default_value, std::string limit) {
  ParameterInfo info;
  info.name = std::move(name);
  info.units = std::move(units);
  info.description = std::move(description);
  info.kind = ParameterKind::kReal;
  info.group = group;
  info.default_value = default_value;
  const InputLimit& range = RequireInputLimit(limit);
  GESWEEP_DEMAND(range.units == info.units);
  info.limit = std::move(limit);
  info.minimum = range.minimum;
  info.maximum = range.maximum;
  info.minimum_exclusive = range.minimum_exclusive;
  info.maximum_exclusive = range.maximum_exclusive;
  return info;
}

// A boolean or a choice: no range, held as the index of its level.
ParameterInfo Levels(std::string name, std::string description, ParameterKind kind, double default_value,
                     std::vector<std::string> levels) {
  ParameterInfo info;
  info.name = std::move(name);
  info.units = "1";
  info.description = std::move(description);
  info.kind = kind;
  info.group = ParameterGroup::kModel;
  info.default_value = default_value;
  info.levels = std::move(levels);
  return info;
}

std::vector<ParameterInfo> BuildCatalog() {
  std::vector<ParameterInfo> c;
  using G = ParameterGroup;

  // The flight condition.
  c.push_back(Real("height_m", "m",
                   "Height H of the mean aerodynamic chord above ground: the evaluation height (modes), "
                   "the start height (open_loop, landing)",
                   G::kFlight, std::nullopt, "height_m"));
  c.push_back(Real("speed_mps", "m/s", "Reference forward speed u0", G::kFlight, std::nullopt, "speed_mps"));

  // Model switches (docs/model.md §2-§4).
  c.push_back(Levels("h_derivatives", "Whether Xh, Zh and Mh are in the model (docs/model.md §4)",
                     ParameterKind::kBoolean, 1.0, {"false", "true"}));
  c.push_back(Levels("cdh", "How CDh is obtained: polar = d(k CLo^2)/dh, zero (docs/model.md §3)",
                     ParameterKind::kChoice, 0.0, EnumLevels<CdhMode>()));
  c.push_back(Levels("interpolation", "Table interpolation in height: linear or pchip (docs/model.md §2)",
                     ParameterKind::kChoice, 0.0, EnumLevels<Interpolation>()));

  // Multiplicative scale factors on every coefficient column and on CDo.
  for (std::string_view name : kCoefficientNames) {
    c.push_back(Real("scale." + std::string(name), "1",
                     "Multiplicative factor on the coefficient " + std::string(name) + " at every height",
                     G::kModel, 1.0, "scale_factor"));
  }
  c.push_back(Real("scale.CDo", "1", "Multiplicative factor on the parasite drag coefficient CDo", G::kModel,
                   1.0, "scale_factor"));

  // Mass properties; the defaults are the aircraft's (DefaultValue).
  c.push_back(Real("mass_kg", "kg", "Airplane mass m (default: the aircraft file's)", G::kModel, std::nullopt,
                   "mass_kg"));
  c.push_back(Real("pitch_inertia_kgm2", "kg m^2",
                   "Pitching moment of inertia Iy (default: the aircraft file's)", G::kModel, std::nullopt,
                   "pitch_inertia_kgm2"));
  c.push_back(Real("cg_shift_over_chord", "1",
                   "CG moved aft by this fraction of the mean chord (negative: forward)", G::kModel, 0.0,
                   "cg_shift_over_chord"));

  // Open-loop perturbation (docs/model.md §7).
  c.push_back(Real("pulse_amplitude_deg", "deg",
                   "Elevator pulse amplitude, positive trailing edge down (paper: 5 deg)", G::kOpenLoop, 5.0,
                   "pulse_amplitude_deg"));
  c.push_back(Real("pulse_duration_s", "s", "Elevator pulse duration (paper: 0.2 s)", G::kOpenLoop, 0.2,
                   "pulse_duration_s"));

  // Landing controller (docs/model.md §8; engine/control/landing_config.h, docs/landing.md). A NaN
  // default means "automatic": the controller's own rule.
  {
    c.push_back(Real("glide_slope_deg", "deg",
                     "Glide-slope angle gamma, positive for a descent (the paper: 2.5 to 3 deg)", G::kLanding,
                     2.5, "glide_slope_deg"));
    c.push_back(Real("flare_height_m", "m", "Height Ho at which the flare starts", G::kLanding, 10.0,
                     "flare_height_m"));
    c.push_back(Real("flare_tau_s", "s",
                     "Time constant tau of the exponential flare command (default NaN: automatic, "
                     "Ho/(u0 sin gamma), so the commanded sink rate is continuous at Ho)",
                     G::kLanding, std::numeric_limits<double>::quiet_NaN(), "flare_tau_s"));
    const char* states[] = {"delta_u",  "delta_w",   "pitch_rate",  "delta_theta",   "delta_h",
                            "elevator", "deviation", "compensator", "error_integral"};
    for (const char* state : states) {
      c.push_back(Real(std::string("lqr.q_") + state, "1",
                       std::string("LQR weight on the state ") + state +
                           " of the paper's Eq. (14) (diagonal of Q; the paper: identity)",
                       G::kLanding, 1.0, "lqr.q"));
    }
    c.push_back(
        Real("lqr.r", "1", "LQR weight R on the elevator command (the paper: 1)", G::kLanding, 1.0, "lqr.r"));
  }

  // The moving atmosphere (docs/model.md §9): every command-line field of DisturbanceOptions::Describe
  // is a run parameter of the same name, unit, range and default (read by open_loop and landing),
  // and the seed of the run's turbulence (RunNoise(seed, run index), docs/disturbance.md).
  for (const FieldRecord& field : ListFields(DisturbanceOptions{})) {
    const FieldAttributes& a = field.attributes;
    if (a.scope != FieldScope::kCommandLineOnly) continue;
    if (field.kind == FieldKind::kNumber) {
      const std::string limit(a.limit.empty() ? a.key : a.limit);
      c.push_back(Real(std::string(a.key), std::string(a.unit), std::string(a.doc), G::kFlight, *field.number,
                       limit));
    } else {
      GESWEEP_DEMAND(field.kind == FieldKind::kChoice);
      const auto code = std::find(field.levels.begin(), field.levels.end(), field.default_text);
      ParameterInfo info = Levels(std::string(a.key), std::string(a.doc), ParameterKind::kChoice,
                                  static_cast<double>(code - field.levels.begin()), field.levels);
      info.group = G::kFlight;
      c.push_back(std::move(info));
    }
  }
  c.push_back(Real("seed", "1",
                   "Seed of the run's turbulence: run i of a sweep flies RunNoise(seed, i) "
                   "(docs/disturbance.md); a whole number",
                   G::kFlight, 0.0, "seed"));

  // Inputs of the verification models (Ishigami, linear): dimensionless, no default meaning.
  for (int i = 1; i <= 8; ++i) {
    std::string name = "x";
    name += std::to_string(i);
    c.push_back(Real(name, "1", "Input " + name + " of the verification models", G::kVerification, 0.0,
                     "verification_input"));
  }
  return c;
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
  return DescribeLimit(RequireInputLimit(info.limit));
}

std::string CheckParameterValue(ParameterId id, double value, const Aircraft* aircraft) {
  const ParameterInfo& info = ParameterCatalog().at(id);
  if (info.kind != ParameterKind::kReal) {
    const bool is_level = std::isfinite(value) && value >= 0 &&
                          value < static_cast<double>(info.levels.size()) && value == std::floor(value);
    return is_level ? "" : "expected " + DescribeAllowedValues(id);
  }
  const InputLimit& limit = RequireInputLimit(info.limit);
  std::string problem = LimitProblem(limit, value);
  if (!problem.empty()) return problem;
  if (info.name == "seed" && value != std::floor(value)) return "expected a whole number";
  if (aircraft != nullptr && info.name == "height_m") {
    if (value < aircraft->wheel_contact_height_m) {
      return "expected a height >= the wheel-contact height " +
             ShortNumber(aircraft->wheel_contact_height_m) + " m of " + aircraft->source_path;
    }
    if (aircraft->field_elevation_m + value > limit.maximum) {
      return "expected field elevation + height <= " + ShortNumber(limit.maximum) +
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
  return ShortNumber(value);
}

std::optional<double> ParseParameterLevel(ParameterId id, std::string_view text) {
  const ParameterInfo& info = ParameterCatalog().at(id);
  for (std::size_t i = 0; i < info.levels.size(); ++i) {
    if (info.levels[i] == text) return static_cast<double>(i);
  }
  return std::nullopt;
}

}  // namespace gesweep

namespace gesweep {
namespace {

// Sets each command-line field of DisturbanceOptions from the run's parameters, in field order.
struct DisturbanceSetter {
  const std::vector<double>* parameters;
  const std::vector<ParameterId>* ids;
  std::size_t next = 0;
  template <class U>
  void operator()(const Field<U>& field) {
    if (field.attributes().scope != FieldScope::kCommandLineOnly) return;
    const double value = (*parameters)[static_cast<std::size_t>((*ids)[next++])];
    if constexpr (NamedEnum<U>) {
      *field.value() = static_cast<U>(static_cast<int>(value));
    } else if constexpr (std::floating_point<U>) {
      *field.value() = value * field.attributes().scale;
    } else {
      GESWEEP_UNREACHABLE();
    }
  }
};

}  // namespace

const std::vector<ParameterId>& DisturbanceParameterIds() {
  static const std::vector<ParameterId> ids = [] {
    std::vector<ParameterId> list;
    for (const FieldRecord& field : ListFields(DisturbanceOptions{})) {
      if (field.attributes.scope == FieldScope::kCommandLineOnly)
        list.push_back(RequireParameter(field.attributes.key));
    }
    list.push_back(RequireParameter("seed"));
    return list;
  }();
  return ids;
}

std::uint64_t ApplyDisturbanceParameters(const std::vector<double>& parameters, DisturbanceOptions& options) {
  const std::vector<ParameterId>& ids = DisturbanceParameterIds();
  DisturbanceSetter setter{&parameters, &ids};
  options.Describe(setter);
  GESWEEP_DEMAND(setter.next + 1 == ids.size());
  return static_cast<std::uint64_t>(parameters[static_cast<std::size_t>(ids.back())]);
}

}  // namespace gesweep
