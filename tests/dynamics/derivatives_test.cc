#include <gtest/gtest.h>

#include "engine/dynamics/longitudinal_model.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// Absolute floor of ExpectRelNear for an expected value of zero.
constexpr double kAbsoluteFloor = 1e-15;
/// The hand value of the ISA density carries 10 significant digits.
constexpr double kDensityTolerance_kgpm3 = 1e-9;
/// Xh comes from CDh, whose hand value carries 7 digits: 1e-8 of an O(1e-3) derivative.
constexpr double kXhTolerance = 1e-8;

// The hand values below carry about 10 significant digits.
constexpr double kRelativeTolerance = 1e-9;

void ExpectRelNear(double actual, double expected, const char* name) {
  EXPECT_NEAR(actual, expected, std::abs(expected) * kRelativeTolerance + kAbsoluteFloor) << name;
}

TEST(Derivatives, MatchHandComputationAtOneTableRow) {
  // ANCE at the table row H = 2.5935 m, u = 32.0208 m/s, worked by hand from docs/model.md §1, §4:
  //  ISA: T/T0 = 1 − 0.0065·2.5935/288.15, exponent g/(R·L) − 1 = 4.255879813,
  //       ρ = 1.225·(T/T0)^4.255879813 = 1.224695024 kg/m³
  //  Q = ½ρu² = 627.8592744 Pa;  Q·S = 1967.020321 N  (S = 3.1329 m²)
  //  Row: CLo 0.3293, CDα 0.1699, CLα 5.4775, CLδe 0.6417, CMα −3.885, CMα̇ −11.03, CMq −18.66,
  //       CMδe −2.699, CLh −0.0007, CMh 0, CDh (docs/model.md §3) 5.995829e-5; m 182.055, Iy 400, c 0.604
  //  Xu  = −2·0.0266·QS/(m·u)              = −0.01795087777
  //  Xw  = −(0.1699 − 0.3293)·QS/(m·u)     =  0.05378514881
  //  Xh  = −CDh·QS/(m·c)                   = −0.001072552519
  //  Zu  = −2·0.3293·QS/(m·u)              = −0.2222264681
  //  Zw  = −(5.4775 + 0.0266)·QS/(m·u)     = −1.857207262
  //  Zh  = 0.0007·QS/(m·c)                 =  0.01252181655
  //  Zδe = −0.6417·QS/m                    = −6.933272582
  //  Mq  = −18.66·(c/2u)·QS·c/Iy           = −0.5227237084
  //  Mw  = −3.885·QS·c/(Iy·u)              = −0.3603666885
  //  Mẇ  = −11.03·(c/2u)·QS·c/(Iy·u)       = −0.009649479619
  //  Mδe = −2.699·QS·c/Iy                  = −8.016571648
  const LongitudinalModel model(LoadAircraftFile(testing::AnceAircraftPath()), ModelOptions{});
  EXPECT_NEAR(model.DensityAt(2.5935), 1.224695024, kDensityTolerance_kgpm3);
  const DimensionalDerivatives d = model.DerivativesAt(2.5935, 32.0208);
  ExpectRelNear(d.Xu, -0.01795087777, "Xu");
  ExpectRelNear(d.Xw, 0.05378514881, "Xw");
  EXPECT_NEAR(d.Xh, -0.001072552519, kXhTolerance);  // CDh's hand value carries 7 digits
  ExpectRelNear(d.Zu, -0.2222264681, "Zu");
  ExpectRelNear(d.Zw, -1.857207262, "Zw");
  ExpectRelNear(d.Zh, 0.01252181655, "Zh");
  ExpectRelNear(d.Zde, -6.933272582, "Zde");
  ExpectRelNear(d.Mq, -0.5227237084, "Mq");
  ExpectRelNear(d.Mw, -0.3603666885, "Mw");
  ExpectRelNear(d.Mw_dot, -0.009649479619, "Mw_dot");
  ExpectRelNear(d.Mde, -8.016571648, "Mde");
  EXPECT_EQ(d.Mh, 0.0);
  EXPECT_EQ(d.Xde, 0.0);
  EXPECT_EQ(d.Mu, 0.0);
}

TEST(StateMatrix, HasTheStructureOfEquationOne) {
  const LongitudinalModel model(LoadAircraftFile(testing::AnceAircraftPath()), ModelOptions{});
  const double u0 = 32.0208;
  const DimensionalDerivatives d = model.DerivativesAt(1.3, u0);
  const Matrix5d A = model.StateMatrix(1.3, u0);
  EXPECT_EQ(A(0, 3), -9.80665);
  EXPECT_EQ(A(1, 2), u0);
  EXPECT_EQ(A(4, 3), u0);
  EXPECT_EQ(A(4, 1), -1.0);
  EXPECT_EQ(A(3, 2), 1.0);
  EXPECT_DOUBLE_EQ(A(2, 2), d.Mq + d.Mw_dot * u0);
  EXPECT_DOUBLE_EQ(A(2, 4), d.Mh + d.Mw_dot * d.Zh);
  const Vector5d B = model.InputMatrix(1.3, u0);
  EXPECT_DOUBLE_EQ(B(2), d.Mde + d.Mw_dot * d.Zde);
  EXPECT_LT(B(2), 0.0);  // positive δe (trailing edge down) pitches the nose down (docs/model.md §1)
}

TEST(StateMatrix, WithoutHDerivativesOnlyTheHeightColumnChanges) {
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  ModelOptions off;
  off.h_derivatives = false;
  const Matrix5d with = LongitudinalModel(ance, ModelOptions{}).StateMatrix(1.0, 30.0);
  const Matrix5d without = LongitudinalModel(ance, off).StateMatrix(1.0, 30.0);
  EXPECT_TRUE(without.col(4).isZero(0.0));
  EXPECT_FALSE(with.col(4).isZero(0.0));
  EXPECT_EQ(with.leftCols(4), without.leftCols(4));
}

}  // namespace
}  // namespace gesweep
