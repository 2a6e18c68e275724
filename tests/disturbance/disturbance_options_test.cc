// The disturbance options: names, the σ_w in force, and one clear error per bad value.
#include "engine/disturbance/disturbance_options.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

TEST(DisturbanceOptions, NamesRoundTrip) {
  EXPECT_EQ(ParseEnum<TurbulenceModel>("dryden"), TurbulenceModel::kDryden);
  EXPECT_EQ(ParseEnum<WindShear>("none"), WindShear::kNone);
  EXPECT_EQ(ParseEnum<GustAxis>("u"), GustAxis::kU);
  EXPECT_FALSE(ParseEnum<GustAxis>("v").has_value());
  EXPECT_EQ(ToString(WindShear::kLogarithmic), "logarithmic");
  EXPECT_EQ(EnumChoices<TurbulenceModel>(), "none or dryden");
}

TEST(DisturbanceOptions, SigmaWFromTheWindOrTheOverride) {
  DisturbanceOptions o;
  o.wind_20ft_mps = -15.433;
  EXPECT_EQ(EffectiveSigmaW(o), 0.0) << "no turbulence";
  o.turbulence = TurbulenceModel::kDryden;
  // 0.1·15.433 in binary is one ulp (2.2e-16) above the literal 1.5433: a rounding or two.
  constexpr double kProductRounding_mps = 1e-15;
  EXPECT_NEAR(EffectiveSigmaW(o), 1.5433, kProductRounding_mps);
  o.turbulence_sigma_w_mps = 0.4;
  EXPECT_EQ(EffectiveSigmaW(o), 0.4);
}

TEST(DisturbanceOptions, EachBadValueNamesItsKey) {
  auto key_of = [](DisturbanceOptions o) {
    try {
      ValidateDisturbanceOptions(o, "study.toml");
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), "study.toml");
      return e.key();
    }
    return std::string("none");
  };
  EXPECT_EQ(key_of({}), "none");
  DisturbanceOptions o;
  o.wind_20ft_mps = std::nan("");
  EXPECT_EQ(key_of(o), "wind_20ft_mps");
  o = {};
  o.turbulence_sigma_w_mps = -1;
  EXPECT_EQ(key_of(o), "turbulence_sigma_w_mps");
  o = {};
  o.turbulence_sample_interval_s = 0;
  EXPECT_EQ(key_of(o), "turbulence_sample_interval_s");
  o = {};
  o.pitch_rate_gust = true;
  EXPECT_EQ(key_of(o), "wing_span_m");
  o = {};
  o.gust_half_length_m = 0;
  EXPECT_EQ(key_of(o), "gust_half_length_m");
  o = {};
  o.gust_start_s = -1;
  EXPECT_EQ(key_of(o), "gust_start_s");
  o = {};
  o.gust_amplitude_mps = INFINITY;
  EXPECT_EQ(key_of(o), "gust_amplitude_mps");
}

}  // namespace
}  // namespace gesweep
