// LandingConfig and the landing's summary described once (engine/common/describe.h): the keys of the
// description are the keys ValidateLandingConfig names, the study table is read from it, and the
// automatic settings (NaN) are replaced by what the landing used.
#include "engine/control/landing_config.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/common/describe_toml.h"
#include "engine/common/errors.h"
#include "engine/common/toml_reader.h"
#include "engine/control/landing_simulation.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

/// The automatic flare time constant by the same closed form as the engine, in doubles: rounding only.
constexpr double kClosedFormTolerance = 1e-12;

const Aircraft& Ance() {
  static const Aircraft aircraft = LoadAircraftFile(testing::AnceAircraftPath().string());
  return aircraft;
}

// The key ValidateLandingConfig names for a config made bad by `spoil`.
template <class Spoil>
std::string KeyOfError(Spoil spoil) {
  LandingConfig config;
  spoil(config);
  try {
    ValidateLandingConfig(config, Ance(), "test");
  } catch (const InputError& error) {
    return error.key();
  }
  return "(valid)";
}

TEST(LandingConfigDescription, KeysAreTheValidationKeys) {
  LandingConfig c;
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.start_height_m = 5.0; }), KeyOf(c, &c.start_height_m));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.start_speed_mps = 1.0; }), KeyOf(c, &c.start_speed_mps));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.glide_slope_deg = 45.0; }), KeyOf(c, &c.glide_slope_deg));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.flare_time_constant_s = -1.0; }),
            KeyOf(c, &c.flare_time_constant_s));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.design_height_m = 0.1; }), KeyOf(c, &c.design_height_m));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.r_weight = 0.0; }), KeyOf(c, &c.r_weight));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.integrator.relative_tolerance = 2.0; }),
            KeyOf(c, &c.integrator.relative_tolerance));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.output_interval_s = -1.0; }), KeyOf(c, &c.output_interval_s));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.flare_asymptote_m = 20.0; }), KeyOf(c, &c.flare_asymptote_m));
  EXPECT_EQ(KeyOfError([](LandingConfig& x) { x.disturbance.gust_half_length_m = 0.0; }),
            KeyOf(c, &c.disturbance.gust_half_length_m));
  // NaN is "automatic" for the settings that say so, and a valid default.
  EXPECT_EQ(KeyOfError([](LandingConfig&) {}), "(valid)");
}

TEST(LandingConfigDescription, StudyTableIsReadFromTheDescription) {
  const toml::table table = ParseToml(
      "design_height_m = 3.0\nplant_height_reference = \"fixed\"\nturbulent_integrator = \"dopri5\"\n"
      "pitch_rate_gust = true\nrelative_tolerance = 1e-4\nreset_compensator_at_flare = true\n",
      "test");
  LandingConfig config;
  ReadFields(TomlSection(table, "test", "analyses.landing"), config);
  EXPECT_EQ(config.design_height_m, 3.0);
  EXPECT_EQ(config.plant_height_reference, PlantHeightReference::kFixedHeight);
  EXPECT_EQ(config.turbulent_integrator, IntegratorKind::kDopri5);
  EXPECT_TRUE(config.disturbance.pitch_rate_gust);
  EXPECT_EQ(config.integrator.relative_tolerance, 1e-4);
  EXPECT_TRUE(config.reset_compensator_at_flare);
  EXPECT_TRUE(std::isnan(config.design_speed_mps));  // absent: automatic

  // A run parameter (the glide slope) is not a study key of the table, nor is a misspelt key.
  for (const char* text : {"glide_slope_deg = 3.0\n", "design_heigth_m = 3.0\n", "seed = 1\n"}) {
    const toml::table bad = ParseToml(text, "test");
    LandingConfig ignored;
    EXPECT_THROW(ReadFields(TomlSection(bad, "test", "analyses.landing"), ignored), InputError) << text;
  }
  // A number outside its limits-table range, named with its key and value.
  const toml::table out_of_range = ParseToml("max_step_s = -1.0\n", "test");
  try {
    LandingConfig ignored;
    ReadFields(TomlSection(out_of_range, "test", "analyses.landing"), ignored);
    ADD_FAILURE() << "max_step_s = -1 was accepted";
  } catch (const InputError& error) {
    EXPECT_EQ(error.key(), "analyses.landing.max_step_s");
    EXPECT_EQ(error.value(), "-1");
  }
}

TEST(LandingConfigDescription, QWeightsAreOneNumberPerStateInEveryVisitor) {
  LandingConfig c;
  c.q_weights[3] = 4.0;
  const auto fields = ListFields(c);
  const auto q = std::find_if(fields.begin(), fields.end(),
                              [](const FieldRecord& f) { return f.attributes.key == "q_weights"; });
  ASSERT_NE(q, fields.end());
  EXPECT_EQ(q->kind, FieldKind::kArray);
  EXPECT_EQ(q->values, (std::vector<double>{1, 1, 1, 4, 1, 1, 1, 1, 1}));
  EXPECT_EQ(ComponentKey(q->attributes, 3), "q_weights.delta_theta");
  // The range check names the component.
  c.q_weights[3] = -1.0;
  try {
    CheckFieldRanges(c, "test");
    ADD_FAILURE() << "a negative weight passed";
  } catch (const InputError& error) {
    EXPECT_EQ(error.key(), "q_weights.delta_theta");
  }
}

TEST(LandingConfigDescription, PlantHeightReferenceNames) {
  EXPECT_EQ(ToString(PlantHeightReference::kReferencePath), "path");
  EXPECT_EQ(ParseEnum<PlantHeightReference>("fixed"), PlantHeightReference::kFixedHeight);
  EXPECT_FALSE(ParseEnum<PlantHeightReference>("ground").has_value());
  EXPECT_EQ(EnumChoices<PlantHeightReference>(), "path or fixed");
}

TEST(LandingConfigDescription, SettingsUsedReplaceTheAutomaticOnes) {
  LandingConfig config;
  config.output_interval_s = 0.0;
  config.time_limit_s = 400.0;  // given: kept
  const LongitudinalModel model(Ance(), ModelOptions{});
  const LandingResult result = SimulateLanding(model, config);
  const LandingConfig used = SettingsUsed(config, result);
  // τ = Ho / (u0 sin γ) (docs/landing.md §5), from the defaults Ho = 10 m, u0 = 52.21 m/s, γ = 2.5°.
  const double tau_s = 10.0 / (52.21 * std::sin(2.5 * std::numbers::pi / 180.0));
  EXPECT_NEAR(used.flare_time_constant_s, tau_s, kClosedFormTolerance * tau_s);
  EXPECT_EQ(used.time_limit_s, 400.0);
  EXPECT_EQ(used.design_height_m, Ance().wheel_contact_height_m);  // the default design height
  EXPECT_EQ(used.design_speed_mps, 52.21);                         // the start speed
  EXPECT_EQ(used.plant_fixed_reference_height_m, Ance().table_heights_m.back());
}

TEST(LandingResultDescription, KeysOfTheSummary) {
  // The summary's output keys, in order (the CSV's columns, the JSON's keys before "design").
  std::vector<std::string> keys;
  for (const FieldRecord& r : ListFields(LandingResult{})) {
    if (r.attributes.in_output) keys.emplace_back(r.attributes.key);
  }
  const std::vector<std::string> expected = {"outcome",
                                             "message",
                                             "touchdown_time_s",
                                             "touchdown_distance_past_transmitter_m",
                                             "touchdown_sink_rate_mps",
                                             "touchdown_pitch_deg",
                                             "touchdown_speed_mps",
                                             "flare_start_time_s",
                                             "glide_path_error_at_flare_m",
                                             "max_abs_elevator_deg",
                                             "max_abs_elevator_command_deg",
                                             "max_abs_pitch_rate_degps",
                                             "saturated_time_s",
                                             "longest_saturation_s",
                                             "min_speed_mps",
                                             "max_speed_mps",
                                             "final_time_s",
                                             "final_height_m",
                                             "touchdown_airspeed_mps",
                                             "flare_max_abs_elevator_deg",
                                             "flare_max_abs_pitch_rate_degps",
                                             "steps",
                                             "rejected_steps",
                                             "rhs_calls"};
  EXPECT_EQ(keys, expected);
}

}  // namespace
}  // namespace gesweep
