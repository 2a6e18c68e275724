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

// The reference and the controller's states of the chunk of lanes [k, k + width of V): LandingProblem's
// ReferenceHeight (the glide path over the ground position, or per lane in the flare its exponential)
// and Command's compensator and integral (per lane with the reset, the free response from the flare
// switch removed). t: the lanes' times (read in the flare only).
template <class Arch, class V>
struct LaneReference {
  V reference, compensator, integral;
};
template <class Arch, class V, int W>
[[gnu::always_inline]] inline LaneReference<Arch, V> ChunkReference(const LandingStepArrays<W>& a, int k,
                                                                    const double* t, const V* x) {
  constexpr int kWidth = kChunkWidth<V>;
  LaneReference<Arch, V> r{Load<Arch, V>(&a.path_start[k]) + Load<Arch, V>(&a.gamma_r[k]) * x[8], x[6], x[7]};
  bool any_flare = false;
  for (int i = 0; i < kWidth; ++i) any_flare = any_flare || a.flare[k + i];
  if (!any_flare) return r;
  alignas(64) double ref[kWidth], comp[kWidth], integ[kWidth];
  Store<Arch>(r.reference, ref);
  Store<Arch>(r.compensator, comp);
  Store<Arch>(r.integral, integ);
  for (int i = 0; i < kWidth; ++i) {
    const int l = k + i;
    if (!a.flare[l]) continue;
    ref[i] = a.flare_asymptote[l] +
             (a.flare_height[l] - a.flare_asymptote[l]) * std::exp(-(t[i] - a.flare_start[l]) / a.tau[l]);
    if (a.reset_at_flare[l]) {
      const double settled = a.integral_at_flare[l] / a.compensator_pole[l];
      comp[i] -= settled + (a.compensator_at_flare[l] - settled) *
                               std::exp(-a.compensator_pole[l] * (t[i] - a.flare_start[l]));
      integ[i] -= a.integral_at_flare[l];
    }
  }
  r.reference = Load<Arch, V>(ref);
  r.compensator = Load<Arch, V>(comp);
  r.integral = Load<Arch, V>(integ);
  return r;
}

// ΔH of the plant: the tracking error e, or per lane H − the fixed reference height.
template <class Arch, class V, int W>
[[gnu::always_inline]] inline V ChunkDeltaH(const LandingStepArrays<W>& a, int k, const V& e,
                                            const double* height) {
  constexpr int kWidth = kChunkWidth<V>;
  bool any_fixed = false;
  for (int i = 0; i < kWidth; ++i) any_fixed = any_fixed || a.fixed_reference[k + i];
  if (!any_fixed) return e;
  alignas(64) double dh[kWidth];
  Store<Arch>(e, dh);
  for (int i = 0; i < kWidth; ++i) {
    if (a.fixed_reference[k + i]) dh[i] = height[i] - a.fixed_reference_height[k + i];
  }
  return Load<Arch, V>(dh);
}

// The air motion at the airplane and the field's derivatives: DisturbanceField::Motion and Evaluate
// without a discrete gust (the height's terms per lane, the rest on the chunk).
template <class Arch, class V>
struct LaneAir {
  V u_g, w_g, q_g, w_g_dot, airspeed;
  V dz, dx1, dx2, dlag;  // the field's state derivatives
};
template <class Arch, class V, int W>
[[gnu::always_inline]] inline LaneAir<Arch, V> ChunkAir(const LandingStepArrays<W>& a, int k, const V* x,
                                                        const double* height, const V& speed_mps) {
  constexpr int kWidth = kChunkWidth<V>;
  const V z = x[9], x1 = x[10], x2 = x[11], lag = x[12];
  alignas(64) double mean_wind[kWidth], sigma_u[kWidth], length_u[kWidth], length_w[kWidth];
  for (int i = 0; i < kWidth; ++i) {
    LaneHeightTerms(a.field[k + i], height[i], mean_wind[i], sigma_u[i], length_u[i], length_w[i]);
  }
  const V zero(0.0);
  const V sigma_w = Load<Arch, V>(&a.sigma_w[k]);
  LaneAir<Arch, V> air;
  const V turbulence_u = Load<Arch, V>(sigma_u) * z;
  const V turbulence_w = sigma_w * (V(kSqrt3) * x1 + V(1.0 - kSqrt3) * x2);
  // Without a discrete gust its term is + 0.0 on whichever axis.
  air.u_g = (Load<Arch, V>(mean_wind) + turbulence_u) + zero;
  air.w_g = turbulence_w + zero;
  air.airspeed = speed_mps - air.u_g;
  // The filters' rates (DrydenRates: a negative airspeed counts as 0), their derivatives and ẇ_g.
  const V v = Select<Arch, V>(air.airspeed > zero, air.airspeed, zero);
  const V a_u = v / Load<Arch, V>(length_u);
  const V a_w = v / Load<Arch, V>(length_w);
  const V gain_u = Sqrt<Arch, V>(V(2.0) * a_u);
  const V gain_w = Sqrt<Arch, V>(a_w);
  air.dz = -a_u * z + gain_u * Load<Arch, V>(&a.noise_u[k]);
  air.dx1 = -a_w * x1 + gain_w * Load<Arch, V>(&a.noise_w[k]);
  air.dx2 = a_w * (x1 - x2);
  air.w_g_dot = sigma_w * (V(kSqrt3) * air.dx1 + V(1.0 - kSqrt3) * air.dx2);
  air.q_g = zero;
  air.dlag = zero;
  bool any_gust = false;
  for (int i = 0; i < kWidth; ++i) any_gust = any_gust || a.pitch_rate_gust[k + i];
  if (any_gust) {  // the pitch-rate gust, per lane
    alignas(64) double on[kWidth];
    for (int i = 0; i < kWidth; ++i) on[i] = a.pitch_rate_gust[k + i] ? 1.0 : 0.0;
    const auto gust = Load<Arch, V>(on) != zero;
    const V pitch_k = Load<Arch, V>(&a.pitch_rate_k[k]);
    const V lead = air.w_g - lag;
    air.q_g = Select<Arch, V>(gust, -(air.w_g - lag) * pitch_k, zero);
    air.dlag = Select<Arch, V>(
        gust, lead * pitch_k * Select<Arch, V>(air.airspeed < zero, zero, air.airspeed), zero);
  }
  return air;
}

// Rows Δu, Δw, q, Δθ, H of the plant: LinearDerivativeTable::DerivativesAt at (H, airspeed), then
// AirRelativeDerivative.
template <class Arch, class V, int W>
[[gnu::always_inline]] inline void ChunkPlant(LandingStepArrays<W>& a, int k, const V* x,
                                              const double* height, const V& delta_h,
                                              const LaneAir<Arch, V>& air,
                                              LinearDerivativeTable::LanesGathered<Arch, V>& gathered,
                                              V* dxdt) {
  using T = LinearDerivativeTable;
  const V du = x[0], dw = x[1], q = x[2], dtheta = x[3], elevator = x[5];
  const V u0 = Load<Arch, V>(&a.u0[k]);
  V d[T::kReducedCount];
  T::DerivativesLanes<Arch, V>(&a.table[k], x[4], height, air.airspeed, &a.hint[k], gathered, d);
  const V du_a = du - air.u_g;
  const V dw_a = dw - air.w_g;
  const V m_u = d[T::kMu] + d[T::kMwDot] * d[T::kZu];
  const V m_w = d[T::kMw] + d[T::kMwDot] * d[T::kZw];
  const V m_q = d[T::kMq] + d[T::kMwDot] * u0;
  const V m_h = d[T::kMh] + d[T::kMwDot] * d[T::kZh];
  const V m_de = d[T::kMde] + d[T::kMwDot] * d[T::kZde];
  dxdt[0] = d[T::kXu] * du_a + d[T::kXw] * dw_a - V(kGravity_mps2) * dtheta + d[T::kXh] * delta_h +
            d[T::kXde] * elevator;
  dxdt[1] = d[T::kZu] * du_a + d[T::kZw] * dw_a + u0 * q + d[T::kZh] * delta_h + d[T::kZde] * elevator;
  const V pitch = m_u * du_a + m_w * dw_a + m_q * q + m_h * delta_h + m_de * elevator;
  // The gust terms of row q only where present (q_g ≠ 0 or ẇ_g ≠ 0, NaN included).
  const V zero(0.0);
  dxdt[2] = Select<Arch, V>((air.q_g == zero) & (air.w_g_dot == zero), pitch,
                            pitch - (d[T::kMq] * air.q_g + d[T::kMwDot] * air.w_g_dot));
  dxdt[3] = q;
  dxdt[4] = -dw + u0 * dtheta;
}

// The closed loop's right-hand side (LandingProblem<true>::Derivative) on the chunk of lanes
// [k, k + width of V) of `a`, at the lanes' times t (read in the flare only) and states x; gathered:
// the chunk's table values of an earlier call of this step, or default-constructed.
template <class Arch, class V, int W>
[[gnu::always_inline]] inline void ChunkLandingDerivative(
    LandingStepArrays<W>& a, int k, const double* t, const V* x, V* dxdt,
    LinearDerivativeTable::LanesGathered<Arch, V>& gathered) {
  constexpr int kWidth = kChunkWidth<V>;
  const V height_m = x[4], elevator = x[5];
  alignas(64) double height[kWidth];
  Store<Arch>(height_m, height);
  const V speed_mps = Load<Arch, V>(&a.u0[k]) + x[0];
  const LaneReference<Arch, V> r = ChunkReference<Arch, V>(a, k, t, x);
  const V e = height_m - r.reference;
  const LaneAir<Arch, V> air = ChunkAir<Arch, V>(a, k, x, height, speed_mps);
  ChunkPlant<Arch, V>(a, k, x, height, ChunkDeltaH<Arch, V>(a, k, e, height), air, gathered, dxdt);
  dxdt[8] = speed_mps;  // the ground speed, to first order
  dxdt[9] = air.dz;
  dxdt[10] = air.dx1;
  dxdt[11] = air.dx2;
  dxdt[12] = air.dlag;
  dxdt[13] = V(0.0);
  // The command −K·z on the air-relative Δu and Δw, clamped to the elevator's limits (std::clamp).
  auto gain = [&](int j) { return Load<Arch, V>(&a.gain[j][k]); };
  const V command =
      -(gain(0) * (x[0] - air.u_g) + gain(1) * (x[1] - air.w_g) + gain(2) * x[2] + gain(3) * x[3] +
        gain(5) * elevator + gain(6) * e + gain(7) * r.compensator + gain(8) * r.integral);
  const V low = Load<Arch, V>(&a.elevator_min[k]);
  const V high = Load<Arch, V>(&a.elevator_max[k]);
  const V clamped = Select<Arch, V>(command < low, low, Select<Arch, V>(high < command, high, command));
  dxdt[5] = Load<Arch, V>(&a.actuator_pole[k]) * (clamped - elevator);
  dxdt[6] = -Load<Arch, V>(&a.compensator_pole[k]) * x[6] + x[7];
  dxdt[7] = -e;
}

template <class Arch, int W>
void LandingKernels::Rk4Stages(LandingStepArrays<W>& a) {
  using V = Chunk<Arch, W>;
  constexpr int N = kLandingLaneStates;
  LinearDerivativeTable::ForEachChunk<Arch, W>(a, [&](int k, auto& gathered) GESWEEP_ALWAYS_INLINE_LAMBDA {
    V x[N], f[N], stage[N], k2[N], k3[N], k4[N], x_new[N], f_new[N];
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
  });
}

template <class Arch, int W>
void LandingKernels::Derivatives(LandingStepArrays<W>& a) {
  using V = Chunk<Arch, W>;
  constexpr int N = kLandingLaneStates;
  LinearDerivativeTable::ForEachChunk<Arch, W>(a, [&](int k, auto& gathered) GESWEEP_ALWAYS_INLINE_LAMBDA {
    V x[N], f[N];
    for (int c = 0; c < N; ++c) x[c] = Load<Arch, V>(&a.x[c][k]);
    ChunkLandingDerivative<Arch>(a, k, &a.t[k], x, f, gathered);
    for (int c = 0; c < N; ++c) Store<Arch>(f[c], &a.f_new[c][k]);
  });
}

}  // namespace gesweep::lanes
