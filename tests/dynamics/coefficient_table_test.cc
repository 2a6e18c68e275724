#include "engine/dynamics/coefficient_table.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/common/errors.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// A coefficient scaled by 1.2 or 2 against the scaled unscaled value: one rounding of an O(1e-3) number.
constexpr double kScalingTolerance = 1e-15;
/// The hand values of CDh (row 0 and row 5) that set the scale of their relative tolerance.
constexpr double kHandValueCDh0 = 8.601892e-4;
constexpr double kHandValueCDh5 = 5.995829e-5;

// Interpolating data that is itself linear in H must reproduce it to rounding.
constexpr double kRoundingTolerance = 1e-12;

// An aircraft whose every column is linear in H: column c holds a_c + b_c·H at uneven heights.
Aircraft LinearAircraft() {
  Aircraft aircraft;
  aircraft.source_path = "<linear>";
  aircraft.wingspan_m = 5;
  aircraft.mean_chord_m = 0.5;
  aircraft.wing_area_m2 = 2.5;
  aircraft.mass_kg = 100;
  aircraft.pitch_inertia_kgm2 = 50;
  aircraft.wheel_contact_height_m = 0.5;
  aircraft.table_heights_m = {0.5, 0.9, 1.7, 3.0, 5.5, 9.0};
  for (double h : aircraft.table_heights_m) {
    CoefficientRow row{};
    for (int c = 0; c < kTabulatedCount; ++c) row[c] = 0.1 * (c + 1) - 0.01 * (c - 7) * h;
    aircraft.rows.push_back(row);
  }
  for (int c = 0; c < kTabulatedCount; ++c) aircraft.free_flight[c] = -42.0 - c;
  return aircraft;
}

double LinearValue(int c, double h) { return 0.1 * (c + 1) - 0.01 * (c - 7) * h; }

TEST(CoefficientTable, LinearAndPchipReproduceLinearDataExactly) {
  for (Interpolation kind : {Interpolation::kLinear, Interpolation::kPchip}) {
    ModelOptions options;
    options.interpolation = kind;
    options.cdh = CdhMode::kZero;
    const CoefficientTable table(LinearAircraft(), options);
    for (double h : {0.5, 0.61, 1.0, 1.7, 2.2, 4.9, 8.99, 9.0}) {
      const CoefficientRow row = table.At(h);
      for (int c = 0; c < kTabulatedCount; ++c) {
        EXPECT_NEAR(row[c], LinearValue(c, h), kRoundingTolerance)
            << ToString(kind) << " c=" << c << " H=" << h;
      }
    }
  }
}

TEST(CoefficientTable, HoldsFirstRowBelowAndFreeFlightAbove) {
  const CoefficientTable table(LinearAircraft(), ModelOptions{});
  EXPECT_EQ(table.At(0.1)[Index(Coefficient::CLo)], LinearValue(Index(Coefficient::CLo), 0.5));
  EXPECT_EQ(table.At(9.0001)[Index(Coefficient::CLo)], -42.0 - Index(Coefficient::CLo));
  EXPECT_EQ(table.At(std::numeric_limits<double>::infinity())[Index(Coefficient::CMq)],
            -42.0 - Index(Coefficient::CMq));
  EXPECT_EQ(table.At(1e6)[Index(Coefficient::CDh)], 0.0);  // CDh is zero in free flight (docs/model.md §3)
}

TEST(CoefficientTable, PchipIsMonotoneOnMonotoneData) {
  // ANCE's CLalpha and CMalphadot rows: CLalpha falls monotonically with height; PCHIP must not
  // overshoot between rows (Fritsch–Carlson property), unlike a natural cubic spline.
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  ModelOptions options;
  options.interpolation = Interpolation::kPchip;
  const CoefficientTable table(ance, options);
  const auto& heights = ance.table_heights_m;
  for (Coefficient c : {Coefficient::CLalpha, Coefficient::CLo, Coefficient::k}) {
    double previous = table.At(heights.front())[Index(c)];
    const bool increasing = ance.rows.back()[Index(c)] > ance.rows.front()[Index(c)];
    for (double h = heights.front(); h <= heights.back(); h += 0.01) {
      const double value = table.At(h)[Index(c)];
      if (increasing) {
        EXPECT_GE(value, previous - kRoundingTolerance) << kCoefficientNames[Index(c)] << " H=" << h;
      } else {
        EXPECT_LE(value, previous + kRoundingTolerance) << kCoefficientNames[Index(c)] << " H=" << h;
      }
      previous = value;
    }
  }
}

TEST(CoefficientTable, PolarCdhMatchesHandComputation) {
  // docs/model.md §3 at the ANCE rows, by hand from Table A2 (c = 0.604 m):
  //  first row (one-sided): f = k·CLo² = 0.0366·0.3392² = 0.004211073 and 0.0403·0.3366² = 0.004565972;
  //   Δh = (1.0374 − 0.7882)/0.604 = 0.4125828; CDh = 0.000354899/0.4125828 = 8.601892e-4.
  //  row H = 2.5935 (central, non-uniform): f0 = 0.0461·0.3305² = 0.005035515 (h0 = 3.435099),
  //   f1 = 0.0471·0.3293² = 0.005107453 (h1 = 4.293874), f2 = 0.0475·0.3288² = 0.005135198 (h2 = 4.964735);
  //   a = 0.858775, b = 0.670861; CDh = (a²f2 − b²f0 + (b² − a²)f1)/(a·b·(a+b)) = 5.995829e-5.
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  const CoefficientTable table(ance, ModelOptions{});
  constexpr double kHandPrecision = 1e-6;  // relative: the hand values carry 7 significant digits
  EXPECT_NEAR(table.rows()[0][Index(Coefficient::CDh)], kHandValueCDh0, kHandValueCDh0 * kHandPrecision);
  EXPECT_NEAR(table.rows()[5][Index(Coefficient::CDh)], kHandValueCDh5, kHandValueCDh5 * kHandPrecision);
  ModelOptions zero;
  zero.cdh = CdhMode::kZero;
  EXPECT_EQ(CoefficientTable(ance, zero).At(1.0)[Index(Coefficient::CDh)], 0.0);
}

TEST(CoefficientTable, ScaleFactorsAndCgShiftApply) {
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  const CoefficientTable base(ance, ModelOptions{});
  ModelOptions options;
  options.coefficient_scale[Index(Coefficient::CLh)] = 1.2;
  options.coefficient_scale[Index(Coefficient::k)] = 2.0;
  const CoefficientTable scaled(ance, options);
  const double h = 1.7;
  EXPECT_NEAR(scaled.At(h)[Index(Coefficient::CLh)], 1.2 * base.At(h)[Index(Coefficient::CLh)],
              kScalingTolerance);
  // CDh = d(k·CLo²)/dh is linear in k, so doubling k doubles CDh.
  EXPECT_NEAR(scaled.At(h)[Index(Coefficient::CDh)], 2.0 * base.At(h)[Index(Coefficient::CDh)],
              kScalingTolerance);

  ModelOptions aft;
  aft.cg_shift_over_chord = 0.1;
  const CoefficientTable shifted(ance, aft);
  // Transfer of moments to a CG 0.1 c aft: CMα' = CMα + 0.1·CLα, e.g. at the first row
  // −4.057 + 0.1·5.953 = −3.4617.
  EXPECT_NEAR(shifted.rows()[0][Index(Coefficient::CMalpha)], -3.4617, kRoundingTolerance);
}

TEST(CoefficientTable, PchipNeedsFourRows) {
  Aircraft aircraft = LinearAircraft();
  aircraft.table_heights_m.resize(3);
  aircraft.rows.resize(3);
  ModelOptions options;
  options.interpolation = Interpolation::kPchip;
  EXPECT_THROW(CoefficientTable(aircraft, options), InputError);
}

}  // namespace
}  // namespace gesweep
