#pragma once
/// The definitions of landing_lanes.h's kernels. Included only by landing_lanes_<isa>.cc, each of which
/// instantiates them for its architecture under its own -m flags (engine/simulation/lanes.h: every
/// template here takes the architecture, and nothing else is instantiated or defined here).
///
/// Each expression is the scalar landing's (landing_simulation.cc's LandingProblem<true>::Derivative,
/// DisturbanceField::Motion and Evaluate, LinearDerivativeTable::DerivativesAt, AirRelativeDerivative,
/// the command and its clamp) with the same operations in the same order, no FMA. Per lane and in scalar
/// code: the table segment and density band, the height's mean wind and Dryden scales (a log and a pow,
/// DisturbanceField::HeightTerms) and, in the flare, the reference's and the compensator's exp.

#include <cmath>
#include <type_traits>

#include "engine/control/landing_lanes.h"
#include "engine/disturbance/dryden.h"
#include "engine/simulation/derivative_table.h"
#include "engine/simulation/lanes.h"

namespace gesweep::lanes {

// xsimd::select and xsimd::sqrt, or their scalar forms when the chunk is a plain double.
template <class Arch, class V, class M>
[[gnu::always_inline]] inline V Select(const M& mask, const V& if_true, const V& if_false) {
  if constexpr (std::is_same_v<V, double>) {
    return mask ? if_true : if_false;
  } else {
    return xsimd::select(mask, if_true, if_false);
  }
}
template <class Arch, class V>
[[gnu::always_inline]] inline V Sqrt(const V& v) {
  if constexpr (std::is_same_v<V, double>) {
    return std::sqrt(v);
  } else {
    return xsimd::sqrt(v);
  }
}

// The closed loop's right-hand side on the chunk of lanes [k, k + width of V) of `a`, at the lanes'
// times t (flare phase only) and states x; gathered: the chunk's table values of an earlier call of
// this step, or default-constructed.
template <class Arch, class V, int W>
[[gnu::always_inline]] inline void ChunkLandingDerivative(LandingStepArrays<W>& a, int k, const double* t,
                                                          const V* x, V* dxdt,
                                                          LinearDerivativeTable::LanesGathered<Arch, V>& gathered) {
  constexpr int kWidth = kChunkWidth<V>;
  using T = LinearDerivativeTable;
  const V du = x[0], dw = x[1], q = x[2], dtheta = x[3], height_m = x[4];
  const V elevator = x[5], compensator_state = x[6], integral_state = x[7], ground = x[8];
  const V z = x[9], x1 = x[10], x2 = x[11], lag = x[12];
  const V u0 = Load<Arch, V>(&a.u0[k]);
  const V speed_mps = u0 + du;

  // ReferenceHeight: the glide path over the ground position, or the flare's exponential (per lane).
  V reference = Load<Arch, V>(&a.path_start[k]) + Load<Arch, V>(&a.gamma_r[k]) * ground;
  // Command's compensator and integral with the free response from the flare switch removed.
  V compensator = compensator_state;
  V integral = integral_state;
  alignas(64) double height[kWidth];
  Store<Arch>(height_m, height);
  {
    bool any_flare = false;
    for (int i = 0; i < kWidth; ++i) any_flare = any_flare || a.flare[k + i];
    if (any_flare) {
      alignas(64) double ref[kWidth], comp[kWidth], integ[kWidth];
      Store<Arch>(reference, ref);
      Store<Arch>(compensator, comp);
      Store<Arch>(integral, integ);
      for (int i = 0; i < kWidth; ++i) {
        const int l = k + i;
        if (!a.flare[l]) continue;
        ref[i] = a.flare_asymptote[l] + (a.flare_height[l] - a.flare_asymptote[l]) *
                                            std::exp(-(t[i] - a.flare_start[l]) / a.tau[l]);
        if (a.reset_at_flare[l]) {
          const double settled = a.integral_at_flare[l] / a.compensator_pole[l];
          comp[i] -= settled + (a.compensator_at_flare[l] - settled) *
                                   std::exp(-a.compensator_pole[l] * (t[i] - a.flare_start[l]));
          integ[i] -= a.integral_at_flare[l];
        }
      }
      reference = Load<Arch, V>(ref);
      compensator = Load<Arch, V>(comp);
      integral = Load<Arch, V>(integ);
    }
  }
  const V e = height_m - reference;
  V delta_h = e;
  {
    bool any_fixed = false;
    for (int i = 0; i < kWidth; ++i) any_fixed = any_fixed || a.fixed_reference[k + i];
    if (any_fixed) {
      alignas(64) double dh[kWidth];
      Store<Arch>(e, dh);
      for (int i = 0; i < kWidth; ++i) {
        if (a.fixed_reference[k + i]) dh[i] = height[i] - a.fixed_reference_height[k + i];
      }
      delta_h = Load<Arch, V>(dh);
    }
  }

  // DisturbanceField::Motion: the height's terms per lane, the rest on the chunk.
  alignas(64) double mean_wind[kWidth], sigma_u[kWidth], length_u[kWidth], length_w[kWidth];
  for (int i = 0; i < kWidth; ++i) {
    LaneHeightTerms(a.field[k + i], height[i], mean_wind[i], sigma_u[i], length_u[i], length_w[i]);
  }
  const V sigma_w = Load<Arch, V>(&a.sigma_w[k]);
  const V turbulence_u = Load<Arch, V>(sigma_u) * z;
  const V turbulence_w = sigma_w * (V(kSqrt3) * x1 + V(1.0 - kSqrt3) * x2);
  // Without a discrete gust its term is + 0.0 on whichever axis.
  const V u_g = (Load<Arch, V>(mean_wind) + turbulence_u) + V(0.0);
  const V w_g = turbulence_w + V(0.0);
  const V airspeed = speed_mps - u_g;
  bool any_gust = false;
  for (int i = 0; i < kWidth; ++i) any_gust = any_gust || a.pitch_rate_gust[k + i];
  const V pitch_k = Load<Arch, V>(&a.pitch_rate_k[k]);
  V q_g(0.0);
  // DisturbanceField::Evaluate: the filters' rates, their derivatives and ẇ_g.
  const V zero(0.0);
  const V v = Select<Arch, V>(airspeed > zero, airspeed, zero);
  const V a_u = v / Load<Arch, V>(length_u);
  const V a_w = v / Load<Arch, V>(length_w);
  const V gain_u = Sqrt<Arch, V>(V(2.0) * a_u);
  const V gain_w = Sqrt<Arch, V>(a_w);
  const V dz = -a_u * z + gain_u * Load<Arch, V>(&a.noise_u[k]);
  const V dx1 = -a_w * x1 + gain_w * Load<Arch, V>(&a.noise_w[k]);
  const V dx2 = a_w * (x1 - x2);
  const V w_g_dot = sigma_w * (V(kSqrt3) * dx1 + V(1.0 - kSqrt3) * dx2);
  V dlag(0.0);
  if (any_gust) {
    const auto gust = [&] {
      alignas(64) double m[kWidth];
      for (int i = 0; i < kWidth; ++i) m[i] = a.pitch_rate_gust[k + i] ? 1.0 : 0.0;
      return Load<Arch, V>(m) != zero;
    }();
    q_g = Select<Arch, V>(gust, -(w_g - lag) * pitch_k, zero);
    const V lead = w_g - lag;
    dlag = Select<Arch, V>(gust, lead * pitch_k * Select<Arch, V>(airspeed < zero, zero, airspeed), zero);
  }

  // LinearDerivativeTable::DerivativesAt at (H, airspeed), then AirRelativeDerivative.
  V d[T::kReducedCount];
  T::DerivativesLanes<Arch, V>(&a.table[k], height_m, height, airspeed, &a.hint[k], gathered, d);
  const V du_a = du - u_g;
  const V dw_a = dw - w_g;
  const V m_u = d[T::kMu] + d[T::kMwDot] * d[T::kZu];
  const V m_w = d[T::kMw] + d[T::kMwDot] * d[T::kZw];
  const V m_q = d[T::kMq] + d[T::kMwDot] * u0;
  const V m_h = d[T::kMh] + d[T::kMwDot] * d[T::kZh];
  const V m_de = d[T::kMde] + d[T::kMwDot] * d[T::kZde];
  dxdt[0] = d[T::kXu] * du_a + d[T::kXw] * dw_a - V(kGravity_mps2) * dtheta + d[T::kXh] * delta_h +
            d[T::kXde] * elevator;
  dxdt[1] = d[T::kZu] * du_a + d[T::kZw] * dw_a + u0 * q + d[T::kZh] * delta_h + d[T::kZde] * elevator;
  const V pitch = m_u * du_a + m_w * dw_a + m_q * q + m_h * delta_h + m_de * elevator;
  dxdt[2] = Select<Arch, V>((q_g == zero) & (w_g_dot == zero), pitch,
                          pitch - (d[T::kMq] * q_g + d[T::kMwDot] * w_g_dot));
  dxdt[3] = q;
  dxdt[4] = -dw + u0 * dtheta;
  dxdt[8] = speed_mps;
  dxdt[9] = dz;
  dxdt[10] = dx1;
  dxdt[11] = dx2;
  dxdt[12] = dlag;
  dxdt[13] = zero;

  // The command −K·z on the air-relative Δu and Δw, clamped to the elevator's limits.
  auto gain = [&](int j) { return Load<Arch, V>(&a.gain[j][k]); };
  const V command = -(gain(0) * du_a + gain(1) * dw_a + gain(2) * q + gain(3) * dtheta + gain(5) * elevator +
                      gain(6) * e + gain(7) * compensator + gain(8) * integral);
  const V low = Load<Arch, V>(&a.elevator_min[k]);
  const V high = Load<Arch, V>(&a.elevator_max[k]);
  const V clamped = Select<Arch, V>(command < low, low, Select<Arch, V>(high < command, high, command));
  dxdt[5] = Load<Arch, V>(&a.actuator_pole[k]) * (clamped - elevator);
  dxdt[6] = -Load<Arch, V>(&a.compensator_pole[k]) * compensator_state + integral_state;
  dxdt[7] = -e;
}

template <class Arch, int W>
void LandingRk4Stages(LandingStepArrays<W>& a) {
  using V = Chunk<Arch, W>;
  constexpr int N = kLandingLaneStates;
  for (int k = 0; k < W; k += kChunkWidth<V>) {
    V x[N], f[N], stage[N], k2[N], k3[N], k4[N], x_new[N], f_new[N];
    LinearDerivativeTable::LanesGathered<Arch, V> gathered;
    for (int c = 0; c < N; ++c) {
      x[c] = Load<Arch, V>(&a.x[c][k]);
      f[c] = Load<Arch, V>(&a.f[c][k]);
    }
    const V h = Load<Arch, V>(&a.h[k]);
    const V half_h = Load<Arch, V>(&a.half_h[k]);
    const V sixth_h = Load<Arch, V>(&a.sixth_h[k]);
    // Rk4Method::Advance's arithmetic, in its order.
    for (int c = 0; c < N; ++c) stage[c] = x[c] + half_h * f[c];
    ChunkLandingDerivative<Arch>(a, k, &a.t_mid[k], stage, k2, gathered);
    for (int c = 0; c < N; ++c) stage[c] = x[c] + half_h * k2[c];
    ChunkLandingDerivative<Arch>(a, k, &a.t_mid[k], stage, k3, gathered);
    for (int c = 0; c < N; ++c) stage[c] = x[c] + h * k3[c];
    ChunkLandingDerivative<Arch>(a, k, &a.t_to[k], stage, k4, gathered);
    for (int c = 0; c < N; ++c) x_new[c] = x[c] + sixth_h * ((f[c] + k4[c]) + V(2.0) * (k2[c] + k3[c]));
    ChunkLandingDerivative<Arch>(a, k, &a.t_to[k], x_new, f_new, gathered);
    for (int c = 0; c < N; ++c) {
      Store<Arch>(x_new[c], &a.x_new[c][k]);
      Store<Arch>(f_new[c], &a.f_new[c][k]);
    }
  }
}

template <class Arch, int W>
void LandingDerivatives(LandingStepArrays<W>& a) {
  using V = Chunk<Arch, W>;
  constexpr int N = kLandingLaneStates;
  for (int k = 0; k < W; k += kChunkWidth<V>) {
    V x[N], f[N];
    LinearDerivativeTable::LanesGathered<Arch, V> gathered;
    for (int c = 0; c < N; ++c) x[c] = Load<Arch, V>(&a.x[c][k]);
    ChunkLandingDerivative<Arch>(a, k, &a.t[k], x, f, gathered);
    for (int c = 0; c < N; ++c) Store<Arch>(f[c], &a.f_new[c][k]);
  }
}

}  // namespace gesweep::lanes

/// Instantiates the landing kernels of architecture ARCH for the widths 1, 2, 4 and 8.
#define GESWEEP_INSTANTIATE_LANDING_LANE_KERNELS(ARCH)                \
  namespace gesweep::lanes {                                          \
  template void LandingRk4Stages<ARCH, 1>(LandingStepArrays<1>&);     \
  template void LandingRk4Stages<ARCH, 2>(LandingStepArrays<2>&);     \
  template void LandingRk4Stages<ARCH, 4>(LandingStepArrays<4>&);     \
  template void LandingRk4Stages<ARCH, 8>(LandingStepArrays<8>&);     \
  template void LandingDerivatives<ARCH, 1>(LandingStepArrays<1>&);   \
  template void LandingDerivatives<ARCH, 2>(LandingStepArrays<2>&);   \
  template void LandingDerivatives<ARCH, 4>(LandingStepArrays<4>&);   \
  template void LandingDerivatives<ARCH, 8>(LandingStepArrays<8>&);   \
  }                                                                   \
  static_assert(true)
