#include "engine/analyses/parameter_catalog.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/aircraft/coefficient.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/control/landing_config.h"
#include "engine/disturbance/disturbance_options.h"
#include "engine/dynamics/model_options.h"
#include "engine/simulation/open_loop.h"

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
ParameterInfo Levels(std::string name, std::string description, ParameterKind kind, ParameterGroup group,
                     double default_value, std::vector<std::string> levels) {
  ParameterInfo info;
  info.name = std::move(name);
  info.units = "1";
  info.description = std::move(description);
  info.kind = kind;
  info.group = group;
  info.default_value = default_value;
  info.levels = std::move(levels);
  return info;
}

// The entry of a described run parameter (RunParameter, describe.h): its key, unit, description,
// limits-table range (the entry of its key unless it names one) and default; a choice's levels from
// its enum's names table.
ParameterInfo FromField(const FieldRecord& field, ParameterGroup group) {
  const FieldAttributes& a = field.attributes;
  switch (field.kind) {
    case FieldKind::kNumber:
      return Real(std::string(a.key), std::string(a.unit), std::string(a.doc), group, *field.number,
                  std::string(a.limit.empty() ? a.key : a.limit));
    case FieldKind::kBoolean:
      return Levels(std::string(a.key), std::string(a.doc), ParameterKind::kBoolean, group,
                    field.default_text == "true" ? 1.0 : 0.0, {"false", "true"});
    case FieldKind::kChoice: {
      const auto code = std::find(field.levels.begin(), field.levels.end(), field.default_text);
      GESWEEP_DEMAND(code != field.levels.end());
      return Levels(std::string(a.key), std::string(a.doc), ParameterKind::kChoice, group,
                    static_cast<double>(code - field.levels.begin()), field.levels);
    }
    default:
      GESWEEP_UNREACHABLE();  // a run parameter is a number, a bool, a named enum or a setting's array
  }
}

// The entries of a setting's array (named_components): one number per component, `<key>.<name>`,
// with the field's unit and range; "<component>" in its description is the component's name.
void AppendComponents(std::vector<ParameterInfo>& c, const FieldRecord& field, ParameterGroup group) {
  const FieldAttributes& a = field.attributes;
  const auto described = [&](std::string_view name) {
    std::string doc(a.doc);
    const std::string_view placeholder = "<component>";
    const std::size_t at = doc.find(placeholder);
    if (at != std::string::npos) doc.replace(at, placeholder.size(), name);
    return doc;
  };
  GESWEEP_DEMAND(a.named_components && field.values.size() == a.components.size());
  for (std::size_t i = 0; i < a.components.size(); ++i) {
    c.push_back(Real(ComponentKey(a, i), std::string(a.unit), described(a.components[i].name), group,
                     field.values[i], std::string(a.limit.empty() ? a.key : a.limit)));
  }
}

// Appends the entries of `object`'s run parameters in field order, with `by_hand` in their struct
// place: just before the field `by_hand_before` (the catalogue's order is the archive's). A key
// already catalogued (the flight condition) or in `elsewhere` (a nested description catalogued in its
// own group) is not appended again; one already catalogued must have the same unit and range.
template <class T>
void AppendDescribed(std::vector<ParameterInfo>& c, const T& object, ParameterGroup group,
                     const std::vector<std::string>& elsewhere, std::vector<ParameterInfo> by_hand = {},
                     std::string_view by_hand_before = {}) {
  for (const FieldRecord& field : ListFields(object)) {
    if (!field.attributes.run_parameter) continue;
    const std::string key(field.attributes.key);
    if (key == by_hand_before) {
      for (ParameterInfo& info : by_hand) c.push_back(std::move(info));
      by_hand.clear();
    }
    const auto known =
        std::find_if(c.begin(), c.end(), [&](const ParameterInfo& i) { return i.name == key; });
    if (known != c.end()) {
      GESWEEP_DEMAND(known->units == field.attributes.unit && known->limit == field.attributes.limit);
      continue;
    }
    if (std::find(elsewhere.begin(), elsewhere.end(), key) != elsewhere.end()) continue;
    if (field.kind == FieldKind::kArray) {
      AppendComponents(c, field, group);
    } else {
      c.push_back(FromField(field, group));
    }
  }
  GESWEEP_DEMAND(by_hand.empty());  // `by_hand_before` is one of the run parameters
}

// The model options' entries by hand (ModelOptions::Describe says why): the scale factors and the
// mass properties, whose defaults are the aircraft's (DefaultValue).
std::vector<ParameterInfo> ModelEntriesByHand() {
  using G = ParameterGroup;
  std::vector<ParameterInfo> c;
  for (std::string_view name : kCoefficientNames) {
    c.push_back(Real("scale." + std::string(name), "1",
                     "Multiplicative factor on the coefficient " + std::string(name) + " at every height",
                     G::kModel, 1.0, "scale_factor"));
  }
  c.push_back(Real("scale.CDo", "1", "Multiplicative factor on the parasite drag coefficient CDo", G::kModel,
                   1.0, "scale_factor"));
  c.push_back(Real("mass_kg", "kg", "Airplane mass m (default: the aircraft file's)", G::kModel, std::nullopt,
                   "mass_kg"));
  c.push_back(Real("pitch_inertia_kgm2", "kg m^2",
                   "Pitching moment of inertia Iy (default: the aircraft file's)", G::kModel, std::nullopt,
                   "pitch_inertia_kgm2"));
  return c;
}

std::vector<std::string> KeysOf(const std::vector<FieldRecord>& fields) {
  std::vector<std::string> keys;
  for (const FieldRecord& field : fields) keys.emplace_back(field.attributes.key);
  return keys;
}

std::vector<ParameterInfo> BuildCatalog() {
  std::vector<ParameterInfo> c;
  using G = ParameterGroup;

  // The flight condition, every analysis's (the open loop's and the landing's start).
  c.push_back(Real("height_m", "m",
                   "Height H of the mean aerodynamic chord above ground: the evaluation height (modes), "
                   "the start height (open_loop, landing)",
                   G::kFlight, std::nullopt, "height_m"));
  c.push_back(Real("speed_mps", "m/s", "Reference forward speed u0", G::kFlight, std::nullopt, "speed_mps"));

  // The model options (docs/model.md §2-§4), the scale factors and mass properties in their place.
  const std::vector<std::string> atmosphere = KeysOf(ListFields(DisturbanceOptions{}));
  AppendDescribed(c, ModelOptions{}, G::kModel, {}, ModelEntriesByHand(), "cg_shift_over_chord");
  // The open-loop perturbation (docs/model.md §7) and the landing controller (docs/model.md §8,
  // docs/landing.md); a NaN default means "automatic": the controller's own rule.
  AppendDescribed(c, OpenLoopConfig{}, G::kOpenLoop, atmosphere);
  AppendDescribed(c, LandingConfig{}, G::kLanding, atmosphere);
  // The moving atmosphere (docs/model.md §9), read by open_loop and landing, and the seed of the
  // run's turbulence (RunNoise(seed, run index), docs/disturbance.md).
  AppendDescribed(c, DisturbanceOptions{}, G::kFlight, {});
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
  for (ParameterInfo& info : c) {
    info.identity_name = info.name;
    for (const ParameterRename& rename : RenamedParameters()) {
      if (rename.name == info.name) info.identity_name = rename.older;
    }
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

const std::vector<ParameterRename>& RenamedParameters() {
  static const std::vector<ParameterRename> renames = [] {
    std::vector<ParameterRename> list = {{"flare_tau_s", "flare_time_constant_s"}, {"lqr.r", "r_weight"}};
    for (std::string_view state : LandingStateNames()) {
      list.push_back({"lqr.q_" + std::string(state), "q_weights." + std::string(state)});
    }
    return list;
  }();
  return renames;
}

std::optional<ParameterId> FindParameterOrOlder(std::string_view name, std::string* note) {
  if (const auto id = FindParameter(name)) return id;
  for (const ParameterRename& rename : RenamedParameters()) {
    if (rename.older != name) continue;
    if (note != nullptr) {
      *note = "parameter '" + rename.older + "' is now '" + rename.name +
              "' (the older name is accepted until the next release; docs/sweep.md, \"Renamed parameters\")";
    }
    return RequireParameter(rename.name);
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

const std::vector<ParameterId>& DisturbanceParameterIds() {
  static const std::vector<ParameterId> ids = [] {
    std::vector<ParameterId> list = RunParameterIds<DisturbanceOptions>();
    list.push_back(RequireParameter("seed"));
    return list;
  }();
  return ids;
}

std::uint64_t ApplyDisturbanceParameters(const std::vector<double>& parameters, DisturbanceOptions& options) {
  ApplyRunParameters(parameters, options);
  return static_cast<std::uint64_t>(parameters[static_cast<std::size_t>(DisturbanceParameterIds().back())]);
}

}  // namespace gesweep
