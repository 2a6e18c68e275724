#pragma once
/// The hot path of every time response: Eq. (1) of the paper with its derivatives re-evaluated at
/// the current height and speed (docs/model.md §4, §5, §7). Three pieces, each replaceable by the
/// generic path of LongitudinalModel and tested against it:
///  - Equation1Entries / Equation1Derivative: the 13 non-kinematic entries of A and B and ẋ = A x + B δe
///    written out (A is sparse; the kinematic entries are constants); the frozen-A floor.
///  - DensityPolynomial: ISA ρ(H) as a degree-6 polynomial (Estrin's scheme) over the heights a landing flies
///    through, within 1e-15 of IsaDensity (a pow per call otherwise).
///  - LinearDerivativeTable: for linear interpolation, each dimensional derivative is
///    ρ·u^p·R(H) with R affine in the coefficients, hence linear in H within a table segment; R is
///    precomputed per segment (value and slope), so one evaluation is 14 fused multiply-adds after a
///    segment check that almost always hits the previous segment.

///
/// DensityPolynomial and LinearDerivativeTable are in derivative_table.h, which needs no Eigen: the
/// lanes' translation units, built with other instruction sets, include it and not this header.

#include "engine/aircraft/atmosphere.h"
#include "engine/dynamics/longitudinal_model.h"
#include "engine/simulation/derivative_table.h"

namespace gesweep {

/// The entries of Eq. (1) that depend on the flight condition (docs/model.md §5). Row q holds the
/// composite entries: m_u = Mu + Mẇ·Zu, m_w = Mw + Mẇ·Zw, m_q = Mq + Mẇ·u0, m_h = Mh + Mẇ·Zh,
/// m_de = Mδe + Mẇ·Zδe. Units as in DimensionalDerivatives (per second, per metre, per radian).
struct Equation1Entries {
  double x_u = 0, x_w = 0, x_h = 0, x_de = 0;
  double z_u = 0, z_w = 0, z_h = 0, z_de = 0;
  double m_u = 0, m_w = 0, m_q = 0, m_h = 0, m_de = 0;
};

/// The entries of Eq. (1) from the derivatives; the Mẇ·u0 term uses the kinematic reference speed
/// u0 (m/s), as the kinematic entries do (docs/model.md §7).
inline Equation1Entries EntriesFromDerivatives(const DimensionalDerivatives& d, double reference_speed_mps) {
  Equation1Entries e;
  e.x_u = d.Xu;
  e.x_w = d.Xw;
  e.x_h = d.Xh;
  e.x_de = d.Xde;
  e.z_u = d.Zu;
  e.z_w = d.Zw;
  e.z_h = d.Zh;
  e.z_de = d.Zde;
  e.m_u = d.Mu + d.Mw_dot * d.Zu;
  e.m_w = d.Mw + d.Mw_dot * d.Zw;
  e.m_q = d.Mq + d.Mw_dot * reference_speed_mps;
  e.m_h = d.Mh + d.Mw_dot * d.Zh;
  e.m_de = d.Mde + d.Mw_dot * d.Zde;
  return e;
}

/// ẋ = A x + B δe of Eq. (1) for x = [Δu, Δw, q, Δθ, ΔH] (SI), elevator δe in rad, kinematic
/// reference speed u0 in m/s. Equal to AssembleStateMatrix(d, u0)·x + AssembleInputMatrix(d)·δe.
GESWEEP_ALWAYS_INLINE void Equation1Derivative(const Equation1Entries& e, double reference_speed_mps,
                                               const double* x, double elevator_rad, double* dxdt) {
  const double du = x[0], dw = x[1], q = x[2], dtheta = x[3], dh = x[4];
  dxdt[0] = e.x_u * du + e.x_w * dw - kGravity_mps2 * dtheta + e.x_h * dh + e.x_de * elevator_rad;
  dxdt[1] = e.z_u * du + e.z_w * dw + reference_speed_mps * q + e.z_h * dh + e.z_de * elevator_rad;
  dxdt[2] = e.m_u * du + e.m_w * dw + e.m_q * q + e.m_h * dh + e.m_de * elevator_rad;
  dxdt[3] = q;
  dxdt[4] = -dw + reference_speed_mps * dtheta;
}

/// LinearDerivativeTable::DerivativesAt (declared in derivative_table.h, defined here where
/// DimensionalDerivatives is complete).
GESWEEP_ALWAYS_INLINE DimensionalDerivatives LinearDerivativeTable::DerivativesAt(double height_m,
                                                                                  double speed_mps,
                                                                                  int& segment_hint) const {
  const Segment& seg = SegmentFor(height_m, segment_hint);
  const double y = height_m - seg.reference_m;
  std::array<double, kReducedCount> r;
  for (int j = 0; j < kReducedCount; ++j) r[j] = seg.slope[j] * y + seg.value[j];
  const double rho = density_.At(height_m);
  const double rho_u = rho * speed_mps;
  const double rho_u2 = rho_u * speed_mps;
  DimensionalDerivatives d;
  d.Xu = rho_u * r[kXu];
  d.Xw = rho_u * r[kXw];
  d.Xh = rho_u2 * r[kXh];
  d.Xde = rho_u2 * r[kXde];
  d.Zu = rho_u * r[kZu];
  d.Zw = rho_u * r[kZw];
  d.Zh = rho_u2 * r[kZh];
  d.Zde = rho_u2 * r[kZde];
  d.Mu = rho_u * r[kMu];
  d.Mw = rho_u * r[kMw];
  d.Mq = rho_u * r[kMq];
  d.Mh = rho_u2 * r[kMh];
  d.Mde = rho_u2 * r[kMde];
  d.Mw_dot = rho * r[kMwDot];
  return d;
}

}  // namespace gesweep
