// The run-parameter catalogue (engine/analyses/parameter_catalog.h): the entries of the described run
// parameters (RunParameter, describe.h) are their fields' key, unit, range, default and levels; the
// renamed parameters are found by their older names, with a note, and keep their older names' hash.
#include "engine/analyses/parameter_catalog.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "engine/common/input_limits.h"
#include "engine/control/landing_config.h"
#include "engine/disturbance/disturbance_options.h"
#include "engine/dynamics/model_options.h"
#include "engine/simulation/open_loop.h"

namespace gesweep {
namespace {

// Compares the catalogue entry of every run-parameter field of T with the field; returns the keys.
template <class T>
std::set<std::string> ExpectEntriesFromFields() {
  std::set<std::string> keys;
  // The catalogue entry of `key`, whose unit must be the field's; null (a failure) when there is none.
  const auto entry = [&](const std::string& key, const FieldAttributes& a) -> const ParameterInfo* {
    keys.insert(key);
    const auto id = FindParameter(key);
    if (!id) {
      ADD_FAILURE() << key << " is described as a run parameter but is not in the catalogue";
      return nullptr;
    }
    const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(*id)];
    EXPECT_EQ(info.units, a.unit) << key;
    return &info;
  };
  for (const FieldRecord& field : ListFields(T{})) {
    const FieldAttributes& a = field.attributes;
    if (!a.run_parameter) continue;
    if (field.kind == FieldKind::kArray) {  // a setting's array: one entry per component
      for (std::size_t c = 0; c < a.components.size(); ++c) {
        const std::string key = ComponentKey(a, c);
        const ParameterInfo* info = entry(key, a);
        if (info == nullptr) continue;
        EXPECT_EQ(info->kind, ParameterKind::kReal) << key;
        EXPECT_EQ(info->default_value, field.values[c]) << key;
      }
      continue;
    }
    const std::string key(a.key);
    const ParameterInfo* found = entry(key, a);
    if (found == nullptr) continue;
    const ParameterInfo& info = *found;
    EXPECT_EQ(a.scope, FieldScope::kCommandLineOnly) << key << ": a run parameter is no [analyses] key";
    switch (field.kind) {
      case FieldKind::kNumber: {
        EXPECT_EQ(info.kind, ParameterKind::kReal) << key;
        const InputLimit& range = RequireInputLimit(a.limit.empty() ? a.key : a.limit);
        EXPECT_EQ(info.minimum, range.minimum) << key;
        EXPECT_EQ(info.maximum, range.maximum) << key;
        EXPECT_EQ(info.minimum_exclusive, range.minimum_exclusive) << key;
        EXPECT_EQ(info.maximum_exclusive, range.maximum_exclusive) << key;
        if (info.group == ParameterGroup::kFlight && (key == "height_m" || key == "speed_mps")) break;
        EXPECT_EQ(info.description, a.doc) << key;
        if (!info.default_value) {
          ADD_FAILURE() << key << " has no default";
          break;
        }
        if (std::isnan(*field.number)) {
          EXPECT_TRUE(std::isnan(*info.default_value)) << key;
        } else {
          EXPECT_EQ(*info.default_value, *field.number) << key;
        }
        break;
      }
      case FieldKind::kBoolean:
        EXPECT_EQ(info.kind, ParameterKind::kBoolean) << key;
        EXPECT_EQ(info.levels, (std::vector<std::string>{"false", "true"})) << key;
        EXPECT_EQ(info.description, a.doc) << key;
        EXPECT_EQ(info.default_value, field.default_text == "true" ? 1.0 : 0.0) << key;
        break;
      case FieldKind::kChoice:
        EXPECT_EQ(info.kind, ParameterKind::kChoice) << key;
        EXPECT_EQ(info.levels, field.levels) << key;  // the enum's names table, by code
        EXPECT_EQ(info.description, a.doc) << key;
        if (!info.default_value) {
          ADD_FAILURE() << key << " has no default";
          break;
        }
        EXPECT_EQ(info.levels.at(static_cast<std::size_t>(*info.default_value)), field.default_text) << key;
        break;
      default:
        ADD_FAILURE() << key << ": a run parameter is a number, a bool or a choice";
    }
  }
  return keys;
}

TEST(ParameterCatalog, ModelOptionsEntriesAreTheirDescription) {
  EXPECT_EQ(ExpectEntriesFromFields<ModelOptions>(),
            (std::set<std::string>{"h_derivatives", "cdh", "interpolation", "cg_shift_over_chord"}));
  const ParameterInfo& cdh = ParameterCatalog()[static_cast<std::size_t>(RequireParameter("cdh"))];
  EXPECT_EQ(cdh.levels, (std::vector<std::string>{"polar", "zero"}));
  EXPECT_EQ(cdh.group, ParameterGroup::kModel);
}

TEST(ParameterCatalog, OpenLoopEntriesAreTheirDescription) {
  const std::set<std::string> keys = ExpectEntriesFromFields<OpenLoopConfig>();
  for (const char* key : {"height_m", "speed_mps", "pulse_amplitude_deg", "pulse_duration_s"})
    EXPECT_TRUE(keys.count(key)) << key;
  // The amplitude's field stores radians; its catalogue default is in the key's degrees.
  EXPECT_EQ(
      ParameterCatalog()[static_cast<std::size_t>(RequireParameter("pulse_amplitude_deg"))].default_value,
      5.0);
}

TEST(ParameterCatalog, LandingEntriesAreTheirDescription) {
  const std::set<std::string> keys = ExpectEntriesFromFields<LandingConfig>();
  for (const char* key : {"glide_slope_deg", "flare_height_m", "flare_time_constant_s", "r_weight"})
    EXPECT_TRUE(keys.count(key)) << key;
  const auto& catalog = ParameterCatalog();
  EXPECT_EQ(catalog[static_cast<std::size_t>(RequireParameter("r_weight"))].units, "rad^2");
  EXPECT_EQ(catalog[static_cast<std::size_t>(RequireParameter("r_weight"))].group, ParameterGroup::kLanding);
  // The Q weights (a setting's array), one per state of Eq. (14), between the flare and R as the struct
  // has them, with the field's unit, range and description (its <component> the state).
  const ParameterId first = RequireParameter("q_weights.delta_u");
  EXPECT_EQ(first, RequireParameter("flare_time_constant_s") + 1);
  EXPECT_EQ(RequireParameter("q_weights.error_integral"), first + 8);
  EXPECT_EQ(RequireParameter("r_weight"), first + 9);
  const ParameterInfo& theta = catalog[static_cast<std::size_t>(RequireParameter("q_weights.delta_theta"))];
  EXPECT_EQ(theta.units, "1");
  EXPECT_EQ(theta.limit, "q_weights");
  EXPECT_EQ(theta.default_value, 1.0);
  EXPECT_EQ(
      theta.description,
      "LQR weight on the state delta_theta of the paper's Eq. (14) (diagonal of Q; the paper: identity)");
}

TEST(ParameterCatalog, ARunsQWeightsAreWrittenIntoTheArrayByState) {
  const std::vector<ParameterId>& ids = RunParameterIds<LandingConfig>();
  std::vector<double> run(ParameterCatalog().size(), 0.0);
  for (ParameterId id : ids)  // every other run parameter at its default (a choice: its level)
    run[static_cast<std::size_t>(id)] =
        ParameterCatalog()[static_cast<std::size_t>(id)].default_value.value_or(2.0);
  for (int i = 0; i < kLandingStateCount; ++i) {
    const std::string key = "q_weights." + std::string(LandingStateNames()[static_cast<std::size_t>(i)]);
    ASSERT_NE(std::find(ids.begin(), ids.end(), RequireParameter(key)), ids.end()) << key;
    run[static_cast<std::size_t>(RequireParameter(key))] = 10.0 + i;
  }
  LandingConfig config;
  ApplyRunParameters(run, config);
  for (int i = 0; i < kLandingStateCount; ++i)
    EXPECT_EQ(config.q_weights[static_cast<std::size_t>(i)], 10.0 + i);
  EXPECT_EQ(config.r_weight, 1.0);
}

TEST(ParameterCatalog, DisturbanceEntriesAreTheirDescription) {
  const std::set<std::string> keys = ExpectEntriesFromFields<DisturbanceOptions>();
  EXPECT_TRUE(keys.count("wind_20ft_mps"));
  EXPECT_TRUE(keys.count("turbulence"));
  EXPECT_FALSE(keys.count("turbulence_sample_interval_s"));  // an analysis setting, not a run parameter
}

TEST(ParameterCatalog, OlderNamesFindTheRenamedParameterWithANote) {
  const std::pair<const char*, const char*> renamed[] = {
      {"flare_tau_s", "flare_time_constant_s"},
      {"lqr.r", "r_weight"},
      {"lqr.q_delta_u", "q_weights.delta_u"},
      {"lqr.q_error_integral", "q_weights.error_integral"}};
  for (const auto& [older, name] : renamed) {
    EXPECT_FALSE(FindParameter(older).has_value()) << older;
    std::string note;
    const auto id = FindParameterOrOlder(older, &note);
    ASSERT_TRUE(id.has_value()) << older;
    EXPECT_EQ(*id, RequireParameter(name));
    EXPECT_NE(note.find(std::string("'") + older + "' is now '" + name + "'"), std::string::npos) << note;
    // Run ids and Monte Carlo draws hash the older name, so the rename changes neither.
    EXPECT_EQ(ParameterCatalog()[static_cast<std::size_t>(*id)].identity_name, older);
  }
  std::string note;
  EXPECT_EQ(FindParameterOrOlder("glide_slope_deg", &note), RequireParameter("glide_slope_deg"));
  EXPECT_EQ(note, "");
  EXPECT_EQ(ParameterCatalog()[static_cast<std::size_t>(RequireParameter("glide_slope_deg"))].identity_name,
            "glide_slope_deg");
  EXPECT_FALSE(FindParameterOrOlder("lqr.q_nothing", &note).has_value());
  EXPECT_EQ(RenamedParameters().size(), 11u);
}

TEST(ParameterCatalog, ApplyRunParametersWritesTheDescribedFields) {
  std::vector<double> parameters(static_cast<std::size_t>(ParameterCount()), 0.0);
  auto set = [&](const char* name, double value) {
    parameters[static_cast<std::size_t>(RequireParameter(name))] = value;
  };
  set("h_derivatives", 0.0);
  set("cdh", 1.0);
  set("interpolation", 1.0);
  set("cg_shift_over_chord", 0.05);
  ModelOptions options;
  ApplyRunParameters(parameters, options);
  EXPECT_FALSE(options.h_derivatives);
  EXPECT_EQ(options.cdh, CdhMode::kZero);
  EXPECT_EQ(options.interpolation, Interpolation::kPchip);
  EXPECT_EQ(options.cg_shift_over_chord, 0.05);

  set("glide_slope_deg", 3.0);
  set("flare_time_constant_s", 4.5);
  set("r_weight", 2.0);
  set("wind_20ft_mps", -6.0);
  LandingConfig config;
  ApplyRunParameters(parameters, config);  // the nested moving atmosphere's too
  EXPECT_EQ(config.glide_slope_deg, 3.0);
  EXPECT_EQ(config.flare_time_constant_s, 4.5);
  EXPECT_EQ(config.r_weight, 2.0);
  EXPECT_EQ(config.disturbance.wind_20ft_mps, -6.0);
  EXPECT_EQ(config.start_height_m, LandingConfig{}.start_height_m);  // the flight condition: by hand

  set("pulse_amplitude_deg", 2.0);
  OpenLoopConfig open_loop;
  ApplyRunParameters(parameters, open_loop);
  EXPECT_DOUBLE_EQ(open_loop.elevator.amplitude_rad, 2.0 * std::acos(-1.0) / 180.0);
}

}  // namespace
}  // namespace gesweep
