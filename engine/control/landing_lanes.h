#pragma once
/// The arithmetic of the turbulent landing's lanes (SimulateLandingBatch, landing_simulation.cc),
/// compiled once per instruction set as the open loop's (engine/simulation/open_loop_lanes.h): the RK4
/// stages of one step of W landings and the closed loop's right-hand side on them (Eq. (1) in
/// air-relative form through the derivative table, the Dryden forming filters driven by the held
/// noise, the mean wind and its shear, the glide-slope or flare reference, the LQR command, the
/// actuator and the compensator). The definitions are in landing_lanes_kernel.h, instantiated for
/// xsimd::sse2, xsimd::avx2 and xsimd::avx512f in landing_lanes_sse2.cc, _avx2.cc and _avx512.cc, each
/// built with its own -m flags (engine/control/CMakeLists.txt); this header declares them for the
/// generic code.

#include "engine/simulation/lanes_isa.h"

namespace gesweep {

class LinearDerivativeTable;
class DisturbanceField;

namespace lanes {

/// The landing's states in a moving atmosphere (landing_simulation.cc's SimIndex): Δu, Δw, q, Δθ, H,
/// δe, x_c, ε_c, x_g and the field's five.
inline constexpr int kLandingLaneStates = 14;

/// What the landing kernels read and write for W lanes: component c of lane i at [c][i]. The
/// constants of a lane are its landing's (LandingProblem's), the phase and the held noise those in
/// force over the step.
template <int W>
struct LandingStepArrays {
  static constexpr int N = kLandingLaneStates;
  alignas(64) double x[N][W]{};      ///< the state at the step's start (Derivatives: where f is wanted)
  alignas(64) double f[N][W]{};      ///< the derivative there
  alignas(64) double x_new[N][W]{};  ///< Rk4Stages: the state at the step's end
  alignas(64) double f_new[N][W]{};  ///< Rk4Stages: the derivative there; Derivatives: ẋ(t, x)
  alignas(64) double t[W]{};         ///< the step's start (Derivatives: the time of x), s
  alignas(64) double t_mid[W]{};     ///< t + h/2, s
  alignas(64) double t_to[W]{};      ///< the step's end, s
  alignas(64) double h[W]{}, half_h[W]{}, sixth_h[W]{};

  // Each lane's landing.
  alignas(64) double u0[W]{};                      ///< the reference (start) speed, m/s
  alignas(64) double gamma_r[W]{};                 ///< −γ, rad
  alignas(64) double path_start[W]{};              ///< H0 − d0, m
  alignas(64) double flare_height[W]{};            ///< Ho, m
  alignas(64) double flare_asymptote[W]{};         ///< m
  alignas(64) double tau[W]{};                     ///< the flare's time constant, s
  alignas(64) double elevator_min[W]{};            ///< rad
  alignas(64) double elevator_max[W]{};            ///< rad
  alignas(64) double actuator_pole[W]{};           ///< 1/s
  alignas(64) double compensator_pole[W]{};        ///< 1/s
  alignas(64) double fixed_reference_height[W]{};  ///< m
  alignas(64) double gain[9][W]{};                 ///< K
  alignas(64) double sigma_w[W]{};                 ///< σ_w, m/s
  alignas(64) double pitch_rate_k[W]{};            ///< π/(4b), 1/m (with the pitch-rate gust)
  bool fixed_reference[W]{};                       ///< ΔH from the fixed reference height
  bool reset_at_flare[W]{};                        ///< the compensator's free response removed in the flare
  bool pitch_rate_gust[W]{};
  // Each lane's phase.
  bool flare[W]{};
  alignas(64) double flare_start[W]{};           ///< s
  alignas(64) double compensator_at_flare[W]{};  ///< m·s
  alignas(64) double integral_at_flare[W]{};     ///< m·s
  // The held noise over the step (DisturbanceField::HeldNoise of the step's segment), 1/√s.
  alignas(64) double noise_u[W]{};
  alignas(64) double noise_w[W]{};

  const LinearDerivativeTable* table[W]{};  ///< never null (idle lanes: another lane's)
  int hint[W]{};                            ///< each lane's segment hint
  const DisturbanceField* field[W]{};       ///< never null (idle lanes: another lane's)

  /// The kernels' table values of the lanes' segments, kept across steps (lanes::KeptChunks); the
  /// generic code never reads them.
  alignas(64) unsigned char gathered[kGatheredBytesPerLane * W]{};
  bool gathered_made = false;
};

/// The landing's kernels (definitions in landing_lanes_kernel.h; KernelsFor<LandingKernels, W>
/// picks an instruction set's).
struct LandingKernels {
  template <int W>
  using Arrays = LandingStepArrays<W>;

  /// Rk4Method::Advance's stages for every lane, lane i bit for bit what the scalar landing's step
  /// computes: x_new and f_new = ẋ(t_to, x_new) from x, f, h, half_h, sixth_h, t, t_mid, t_to.
  template <class Arch, int W>
  static void Rk4Stages(LandingStepArrays<W>& lanes);

  /// f_new = ẋ(t, x) for every lane (a restart's derivative; f, the step's, is left as it is): lane
  /// i is its LandingProblem's Derivative bit for bit.
  template <class Arch, int W>
  static void Derivatives(LandingStepArrays<W>& lanes);
};

/// DisturbanceField::HeightTerms of `field` (out of line: the kernels call it per lane).
void LaneHeightTerms(const DisturbanceField* field, double height_m, double& mean_wind_mps,
                     double& sigma_u_mps, double& length_u_m, double& length_w_m);

}  // namespace lanes
}  // namespace gesweep
