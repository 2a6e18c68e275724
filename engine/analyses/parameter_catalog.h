#pragma once
/// The catalogue of every parameter a study can fix or sweep (docs/sweep.md, schemas/study.schema.json):
/// the flight condition, the model switches of docs/model.md, scale factors on every coefficient,
/// mass properties, the open-loop perturbation, the landing controller, and the inputs of the
/// verification models. The unit is in each name; degrees only where the name says `_deg`.
///
/// A run parameter that a settings struct describes (a field marked RunParameter(), describe.h) has
/// its entry from that field: ModelOptions, the open loop's and the landing's start conditions and
/// inputs, DisturbanceOptions. The flight condition (height_m, speed_mps: every analysis's), the
/// arrays (the scale factors, the landing's Q weights), the mass properties, the seed and the
/// verification inputs are written here by hand (docs/architecture.md, "Still by hand").

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/common/describe.h"
#include "engine/common/errors.h"
#include "engine/disturbance/disturbance_options.h"

namespace gesweep {

/// What values a parameter takes. Every value is held as a double: a boolean as 0/1, a choice as
/// the index of its level.
enum class ParameterKind {
  kReal,     ///< a finite number in the parameter's range
  kBoolean,  ///< true/false, held as 1/0
  kChoice,   ///< one of a few names, held as the level index
};

/// Which group of analyses reads a parameter.
enum class ParameterGroup {
  kFlight,        ///< height and speed: read by the analyses that name them
  kModel,         ///< model options, scale factors, mass properties: read by every model analysis
  kOpenLoop,      ///< the open-loop perturbation
  kLanding,       ///< the landing controller
  kVerification,  ///< inputs x1..x8 of the verification models (Ishigami, linear)
};

/// One catalogue entry.
struct ParameterInfo {
  std::string name;         ///< study key, archive dataset name (e.g. "scale.CLh")
  std::string units;        ///< "m", "m/s", "deg", "s", "kg", "kg m^2", "1" for a ratio
  std::string description;  ///< one line, for schemas/archive.md and the archive's attributes
  ParameterKind kind = ParameterKind::kReal;
  ParameterGroup group = ParameterGroup::kModel;
  std::vector<std::string> levels;  ///< names of the values of a choice or boolean
  /// Value when a study neither fixes nor sweeps it; nullopt: it must be given when used.
  /// Mass and pitch inertia default to the aircraft's own (see DefaultValue).
  std::optional<double> default_value;
  /// The entry of the limits table (engine/common/input_limits.h) that holds a real value's range;
  /// empty for a choice or a boolean. The table is the one source of every range: the fields below
  /// are copied from it.
  std::string limit;
  double minimum = 0;  ///< allowed range of a real value, inclusive unless *_exclusive
  double maximum = 0;
  bool minimum_exclusive = false;
  bool maximum_exclusive = false;
  /// The name hashed into run ids (runs/id) and Monte Carlo draws: the first name the parameter had
  /// (its older name when renamed, RenamedParameters), so that a rename changes no run's id or draw.
  std::string identity_name;
};

/// Index of a parameter in the catalogue.
using ParameterId = int;

/// Every parameter, in a fixed order (the order of the archive's fixed-parameter attributes).
const std::vector<ParameterInfo>& ParameterCatalog();

/// Number of catalogue entries.
int ParameterCount();

/// The id of a name, or nullopt.
std::optional<ParameterId> FindParameter(std::string_view name);

/// A run parameter's older name, kept for one release (issue 29: one name per run parameter, the
/// described field's key).
struct ParameterRename {
  std::string older;  ///< "flare_tau_s"
  std::string name;   ///< "flare_time_constant_s"
};

/// Every renamed run parameter: the one table of older names, read by the study (with a note) and by
/// the readers of older archives (docs/sweep.md, "Renamed parameters").
const std::vector<ParameterRename>& RenamedParameters();

/// The id of `name`, or of the parameter whose older name it is (RenamedParameters); nullopt when
/// neither. For an older name, `*note` (when not null) is set to the one line to show: "parameter
/// 'flare_tau_s' is now 'flare_time_constant_s' (the older name is accepted until the next release)".
std::optional<ParameterId> FindParameterOrOlder(std::string_view name, std::string* note);

/// The id of a name the engine itself uses; GESWEEP_DEMAND that it exists.
ParameterId RequireParameter(std::string_view name);

/// All catalogue names (for near-name suggestions).
std::vector<std::string> ParameterNames();

/// The default of a parameter for this aircraft (mass and pitch inertia come from the aircraft;
/// nullopt when the parameter has no default and must be given). `aircraft` may be null when no
/// analysis builds a model.
std::optional<double> DefaultValue(ParameterId id, const Aircraft* aircraft);

/// Checks one value of a parameter. Returns an empty string when it is valid, else what was
/// expected ("expected a number in (0, 1e+06] kg (...)", "expected a height >= the wheel-contact
/// height 0.788 m ..."): the limits table's range and reason, then the aircraft's own limits.
/// `aircraft` (may be null) adds the aircraft-dependent limits (height above wheel contact).
std::string CheckParameterValue(ParameterId id, double value, const Aircraft* aircraft);

/// Renders a value for messages and attributes: a number, or the level name of a choice/boolean.
std::string FormatParameterValue(ParameterId id, double value);

/// Parses a level name of a choice or boolean parameter ("polar", "true"); nullopt when unknown.
std::optional<double> ParseParameterLevel(ParameterId id, std::string_view text);

/// A short description of the allowed values ("one of linear, pchip", "a number in (0, 1e+06] kg").
std::string DescribeAllowedValues(ParameterId id);

namespace catalog_detail {

struct RunParameterSetter {
  const std::vector<double>* parameters;
  const std::vector<ParameterId>* ids;
  std::size_t next = 0;
  template <class U>
  void operator()(const Field<U>& field) {
    if (!field.attributes().run_parameter) return;
    const double value = (*parameters)[static_cast<std::size_t>((*ids)[next++])];
    if constexpr (std::same_as<U, bool>) {
      *field.value() = value != 0.0;
    } else if constexpr (NamedEnum<U>) {
      *field.value() = EnumAt<U>(value);  // a choice's level code is the enum's code
    } else if constexpr (std::floating_point<U>) {
      *field.value() = value * field.attributes().scale;
    } else if constexpr (DoubleArray<U>) {
      // A setting's array: one run parameter per component, the first read above.
      const FieldAttributes& a = field.attributes();
      GESWEEP_DEMAND(a.named_components);
      (*field.value())[0] = value * a.scale;
      for (std::size_t c = 1; c < a.components.size(); ++c) {
        (*field.value())[static_cast<int>(c)] =
            (*parameters)[static_cast<std::size_t>((*ids)[next++])] * a.scale;
      }
    } else {
      GESWEEP_UNREACHABLE();  // a run parameter is a number, a bool, a named enum or a setting's array
    }
  }
};

}  // namespace catalog_detail

/// The run parameters a described struct T holds: its fields marked RunParameter() (describe.h), in
/// field order (a nested description's included).
template <class T>
const std::vector<ParameterId>& RunParameterIds() {
  static const std::vector<ParameterId> ids = [] {
    std::vector<ParameterId> list;
    for (const FieldRecord& field : ListFields(T{})) {
      if (!field.attributes.run_parameter) continue;
      if (field.kind != FieldKind::kArray) {
        list.push_back(RequireParameter(field.attributes.key));
        continue;
      }
      for (std::size_t c = 0; c < field.attributes.components.size(); ++c)
        list.push_back(RequireParameter(ComponentKey(field.attributes, c)));
    }
    return list;
  }();
  return ids;
}

/// Writes a run's values of T's run parameters into `object`: a boolean's level (0, 1) as false and
/// true, a choice's level index as the enum's code, a number in the key's unit times the field's scale.
template <class T>
void ApplyRunParameters(const std::vector<double>& parameters, T& object) {
  const std::vector<ParameterId>& ids = RunParameterIds<T>();
  catalog_detail::RunParameterSetter setter{&parameters, &ids};
  object.Describe(setter);
  GESWEEP_DEMAND(setter.next == ids.size());
}

/// The run parameters of the moving atmosphere, in the order of DisturbanceOptions::Describe's
/// run-parameter fields, then `seed` (docs/model.md §9, docs/disturbance.md).
const std::vector<ParameterId>& DisturbanceParameterIds();

/// Writes a run's values of the disturbance parameters into `options` (a choice's level index is the
/// enum's code) and returns the run's seed.
std::uint64_t ApplyDisturbanceParameters(const std::vector<double>& parameters, DisturbanceOptions& options);

}  // namespace gesweep
