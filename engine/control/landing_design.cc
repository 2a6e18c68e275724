#include "engine/control/landing_design.h"

#include <algorithm>
#include <cstring>
#include <optional>

namespace gesweep {
namespace {

/// Everything the LQR solution of a landing design is computed from: the design model's A, B and C,
/// the weights Q (diagonal) and R. Compared byte for byte, so equal keys mean the same solution.
struct LqrKey {
  double a[kDesignStateCount * kDesignStateCount];
  double b[kDesignStateCount];
  double c[kLandingStateCount * kDesignStateCount];
  double q[kLandingStateCount];
  double r;

  bool operator==(const LqrKey& other) const { return std::memcmp(this, &other, sizeof(LqrKey)) == 0; }
};
static_assert(sizeof(LqrKey) ==
              sizeof(double) * (kDesignStateCount * (kDesignStateCount + 1 + kLandingStateCount) +
                                kLandingStateCount + 1));  // no padding: memcmp compares values only

LqrKey KeyOf(const LandingDesignModel& model, const LandingConfig& config) {
  LqrKey key;
  std::memcpy(key.a, model.A.data(), sizeof(key.a));
  std::memcpy(key.b, model.B.data(), sizeof(key.b));
  std::memcpy(key.c, model.C.data(), sizeof(key.c));
  std::copy(config.q_weights.begin(), config.q_weights.end(), key.q);
  key.r = config.r_weight;
  return key;
}

/// The LQR solutions of this thread's last few designs (kLandingDesignCacheSize): a sweep over the glide
/// slope, the flare or the disturbance at one design point, and every landing of a risk study, designs
/// the same gain again for every landing; Lqry is a pure function of the key, so a solution found here
/// is the one it would compute, bit for bit.
class LqrCache {
 public:
  const LqrResult* Find(const LqrKey& key) const {
    for (const Entry& e : entries_)
      if (e.key && *e.key == key) return &e.result;
    return nullptr;
  }
  void Add(const LqrKey& key, const LqrResult& result) {
    Entry& e = entries_[next_];
    e.key = key;
    e.result = result;
    next_ = (next_ + 1) % entries_.size();
  }

 private:
  struct Entry {
    std::optional<LqrKey> key;
    LqrResult result;
  };
  std::array<Entry, kLandingDesignCacheSize> entries_;
  std::size_t next_ = 0;
};

LqrResult SolveDesign(const LandingDesignModel& model, const LandingConfig& config) {
  StateSpace system;
  system.A = model.A;
  system.B = model.B;
  system.C = model.C;
  system.D = Eigen::MatrixXd::Zero(kLandingStateCount, 1);
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(kLandingStateCount, kLandingStateCount);
  for (int i = 0; i < kLandingStateCount; ++i) Q(i, i) = config.q_weights[i];
  return Lqry(system, Q, Eigen::MatrixXd::Constant(1, 1, config.r_weight));
}

}  // namespace

LandingDesignModel BuildLandingDesignModel(const DimensionalDerivatives& d, double u0,
                                           double actuator_pole_per_s, double compensator_pole_per_s) {
  const Matrix5d A5 = AssembleStateMatrix(d, u0);
  const Vector5d B5 = AssembleInputMatrix(d);
  LandingDesignModel m;
  m.A.setZero();
  m.B.setZero();
  // Rows Δu, Δw, q, Δθ of Eq. (1): the elevator column comes from B, the ΔH column acts on e.
  m.A.block<4, 4>(0, 0) = A5.block<4, 4>(0, 0);
  m.A.block<4, 1>(0, kDesignElevator) = B5.head<4>();
  m.A.block<4, 1>(0, kDesignTrackingError) = A5.block<4, 1>(0, kDeltaH);
  // Actuator Tf3 = Sδ/(s + Sδ).
  m.A(kDesignElevator, kDesignElevator) = -actuator_pole_per_s;
  m.B(kDesignElevator) = actuator_pole_per_s;
  // ė = u0·Δθ − Δw (+ exogenous −u0·γr or H_ref/τ), the ΔH row of Eq. (1).
  m.A.block<1, 4>(kDesignTrackingError, 0) = A5.block<1, 4>(kDeltaH, 0);
  // Compensator: ẋ_c = −S_d·x_c + ε_c (Tf2), ε̇_c = r − e (Tf1).
  m.A(kDesignCompensator, kDesignCompensator) = -compensator_pole_per_s;
  m.A(kDesignCompensator, kDesignErrorIntegral) = 1.0;
  m.A(kDesignErrorIntegral, kDesignTrackingError) = -1.0;
  // Outputs: the 9 states of Eq. (14); ΔH and d both read e.
  constexpr int kSource[kLandingStateCount] = {
      kDesignDeltaU,   kDesignDeltaW,        kDesignPitchRate,   kDesignDeltaTheta,   kDesignTrackingError,
      kDesignElevator, kDesignTrackingError, kDesignCompensator, kDesignErrorIntegral};
  m.C.setZero();
  for (int i = 0; i < kLandingStateCount; ++i) m.C(i, kSource[i]) = 1.0;
  return m;
}

void BuildAugmentedSystem(const DimensionalDerivatives& d, double u0, double actuator_pole_per_s,
                          double compensator_pole_per_s, Eigen::MatrixXd& A, Eigen::MatrixXd& B) {
  enum : int { kH = 4, kDe = 5, kD = 6, kX = 7, kEps = 8 };
  const Matrix5d A5 = AssembleStateMatrix(d, u0);
  const Vector5d B5 = AssembleInputMatrix(d);
  A = Eigen::MatrixXd::Zero(kLandingStateCount, kLandingStateCount);
  B = Eigen::MatrixXd::Zero(kLandingStateCount, 1);
  A.block<5, 5>(0, 0) = A5;
  A.block<5, 1>(0, kDe) = B5;
  A(kDe, kDe) = -actuator_pole_per_s;
  B(kDe, 0) = actuator_pole_per_s;
  A.block<1, 5>(kD, 0) = A5.row(kH);  // ḋ = u0·Δθ − Δw, the same signal as ΔH's
  A(kX, kX) = -compensator_pole_per_s;
  A(kX, kEps) = 1.0;
  A(kEps, kD) = -1.0;
}

LandingDesign DesignLandingController(const LongitudinalModel& model, const LandingConfig& config,
                                      DesignCache cache) {
  LandingDesign design;
  design.design_height_m = SetOr(config.design_height_m, model.aircraft().wheel_contact_height_m);
  design.design_speed_mps = SetOr(config.design_speed_mps, config.start_speed_mps);
  design.design_h_derivatives = config.design_h_derivatives;
  // The table's derivatives with the h-derivatives in, whatever the plant's option says.
  DimensionalDerivatives d =
      ComputeDerivatives(model.CoefficientsAt(design.design_height_m), model.mass_geometry(),
                         model.DensityAt(design.design_height_m), design.design_speed_mps);
  if (!design.design_h_derivatives) d.Xh = d.Zh = d.Mh = 0.0;
  design.model = BuildLandingDesignModel(d, design.design_speed_mps, config.actuator_pole_per_s,
                                         config.compensator_pole_per_s);

  LqrResult lqr;
  if (cache == DesignCache::kUse) {
    thread_local LqrCache solutions;
    const LqrKey key = KeyOf(design.model, config);
    if (const LqrResult* found = solutions.Find(key)) {
      lqr = *found;
    } else {
      lqr = SolveDesign(design.model, config);
      solutions.Add(key, lqr);
    }
  } else {
    lqr = SolveDesign(design.model, config);
  }
  design.status = lqr.status;
  design.message = lqr.message;
  if (!lqr.ok()) return design;
  design.design_gain = lqr.K;
  design.riccati_solution = lqr.S;
  design.closed_loop_eigenvalues = lqr.closed_loop_eigenvalues;
  if (design.closed_loop_eigenvalues.size() > 0)
    design.closed_loop_max_real_per_s = design.closed_loop_eigenvalues[0].real();
  // Back to the paper's 9 states: K_ΔH = 0, the rest read off ζ.
  const auto& k = design.design_gain;
  design.gain = {
      k(kDesignDeltaU),   k(kDesignDeltaW),        k(kDesignPitchRate),   k(kDesignDeltaTheta),   0.0,
      k(kDesignElevator), k(kDesignTrackingError), k(kDesignCompensator), k(kDesignErrorIntegral)};
  return design;
}

}  // namespace gesweep
