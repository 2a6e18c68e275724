#pragma once
/// ISA ρ(H) as a polynomial (DensityPolynomial) and the derivatives of a linearly interpolated table
/// per segment (LinearDerivativeTable): the hot path of every time response (derivative_kernel.h,
/// which includes this header), with their lanes' forms (lanes.h). No Eigen and nothing built with
/// the build's vector flags here: the lanes' translation units (open_loop_lanes_<isa>.cc), built with
/// -mavx2 or -mavx512f, include this header, and Eigen configures itself differently under those flags
/// (the alignment of its fixed-size types among others), which must not differ between translation units.

#include <array>
#include <cmath>
#include <vector>

#include "engine/aircraft/atmosphere.h"
#include "engine/simulation/lanes.h"

/// Forces inlining of the few functions on the per-stage path: GCC otherwise keeps
/// Equation1Derivative out of line (called from five places), which measured 40 % of the
/// frozen-A run.
#define GESWEEP_ALWAYS_INLINE [[gnu::always_inline]] inline
/// A lambda's body inlined into its caller (a kernel's ForEachChunk body):
/// `[&](...) GESWEEP_ALWAYS_INLINE_LAMBDA {`.
#define GESWEEP_ALWAYS_INLINE_LAMBDA __attribute__((always_inline))

namespace gesweep {

class LongitudinalModel;        // engine/dynamics/longitudinal_model.h
struct DimensionalDerivatives;  // idem

/// ISA density ρ(field elevation + H) in kg/m³ without a pow per call: a Taylor polynomial of
/// ρ0 (1 − L z/T0)^(g/(R L) − 1) about the middle of kPolynomialLow_m … kPolynomialHigh_m above
/// the field, evaluated by Estrin's scheme; outside that band, IsaDensity itself. Truncation error < 1e-18
/// relative in the band (the next term), so the result is IsaDensity to rounding (tested to 1e-14).
class DensityPolynomial {
 public:
  static constexpr double kPolynomialLow_m = -100.0;  ///< band of H over which the polynomial is used
  static constexpr double kPolynomialHigh_m = 600.0;  ///< (covers the landing from 500 m)
  static constexpr int kDegree = 6;                   ///< At() writes the degree-6 Estrin scheme out
  static_assert(kDegree == 6);

  /// field_elevation_m: ISA altitude of the ground, m (within the troposphere).
  explicit DensityPolynomial(double field_elevation_m);

  /// ρ at height H above the field, kg/m³. NaN outside the troposphere (as IsaDensity).
  GESWEEP_ALWAYS_INLINE double At(double height_m) const {
    const double y = height_m - center_m_;
    if (!(std::abs(y) <= half_width_m_)) return IsaDensity(field_elevation_m_ + height_m);
    // Estrin's scheme: the same polynomial as Horner's with half the dependent operations.
    const auto& c = coefficients_;
    const double y2 = y * y;
    const double y4 = y2 * y2;
    return ((c[0] + c[1] * y) + (c[2] + c[3] * y) * y2) + ((c[4] + c[5] * y) + c[6] * y2) * y4;
  }

  /// At for the lanes of one chunk on architecture Arch (lanes.h): lane i is polynomials[i]->At(height[i])
  /// bit for bit (the same operations in the same order; a lane outside its band gets IsaDensity).
  /// height_m: the chunk of heights, m; height: the same heights as doubles; center_m and
  /// coefficients: lane i's polynomial's (GatherLanes).
  template <class Arch, class V>
  GESWEEP_ALWAYS_INLINE static V AtLanes(const DensityPolynomial* const* polynomials, const V& height_m,
                                         const double* height, const V& center_m, const V* coefficients) {
    constexpr int kWidth = lanes::kChunkWidth<V>;
    const V y = height_m - center_m;
    const V* c = coefficients;
    const V y2 = y * y;
    const V y4 = y2 * y2;
    V rho = ((c[0] + c[1] * y) + (c[2] + c[3] * y) * y2) + ((c[4] + c[5] * y) + c[6] * y2) * y4;
    alignas(64) double values[kWidth];
    bool outside = false;
    for (int i = 0; i < kWidth; ++i) {
      const DensityPolynomial& p = *polynomials[i];
      if (std::abs(height[i] - p.center_m_) <= p.half_width_m_) continue;
      if (!outside) lanes::Store<Arch>(rho, values);
      outside = true;
      values[i] = IsaDensity(p.field_elevation_m_ + height[i]);
    }
    if (outside) rho = lanes::Load<Arch, V>(values);
    return rho;
  }

  /// The centres and coefficients of the lanes' polynomials as chunks, for AtLanes.
  template <class Arch, class V>
  GESWEEP_ALWAYS_INLINE static void GatherLanes(const DensityPolynomial* const* polynomials, V& center_m,
                                                V* coefficients) {
    center_m = lanes::Gather<Arch, V>([&](int i) { return polynomials[i]->center_m_; });
    for (int k = 0; k <= kDegree; ++k) {
      coefficients[k] = lanes::Gather<Arch, V>([&](int i) { return polynomials[i]->coefficients_[k]; });
    }
  }

 private:
  double field_elevation_m_;
  double center_m_;
  double half_width_m_;
  std::array<double, kDegree + 1> coefficients_{};
};

/// Derivatives of docs/model.md §4 for a model with linear interpolation, arranged per table segment.
/// Each derivative is D = ρ·u^p·R(H) with p = 1 (Xu, Xw, Zu, Zw, Mu, Mw, Mq), p = 2 (Xh, Xδe, Zh,
/// Zδe, Mh, Mδe) or p = 0 (Mẇ), and R(H) = ComputeDerivatives(C(H), mg, ρ = 1, u = 1) is affine in
/// the coefficient row C(H), which is linear in H between two table rows: so R is exactly linear
/// in each segment, constant below the first row and constant (the free-flight row) above the last.
class LinearDerivativeTable {
 public:
  /// Precondition: model.options().interpolation == Interpolation::kLinear (GESWEEP_DEMAND).
  explicit LinearDerivativeTable(const LongitudinalModel& model);

  /// Index of the segment containing H, to seed `segment_hint` of At.
  int SegmentOf(double height_m) const;

  /// Derivatives at height H (m) and speed u (m/s); Xh = Zh = Mh = 0 without h-derivatives.
  /// Same values as model.DerivativesAt(H, u) to rounding, with ρ from DensityPolynomial.
  /// segment_hint: any segment index on entry (the previous call's is best); on return, H's.
  /// Defined in derivative_kernel.h (DimensionalDerivatives is complete there), inlined into the
  /// landing's right-hand side.
  GESWEEP_ALWAYS_INLINE DimensionalDerivatives DerivativesAt(double height_m, double speed_mps,
                                                             int& segment_hint) const;

  /// ẋ of Eq. (1) at x = [Δu, Δw, q, Δθ, ΔH] (SI) and elevator δe (rad), with H = H0 + ΔH and
  /// u = u0 + Δu for the derivatives and the reference u0 (m/s) in the kinematic entries. The hot
  /// path: the speed and density factors come out of the sums, so that the products with the
  /// state run while ρ(H) is being computed, and row q is written q̇ = ΣM·x + Mẇ·ẇ, which is row q
  /// of Eq. (1) (Mẇ·(Zu Δu + Zw Δw + u0 q + Zh ΔH + Zδe δe) = Mẇ·ẇ). segment_hint as above.
  GESWEEP_ALWAYS_INLINE void Equation1(double start_height_m, double reference_speed_mps, const double* x,
                                       double elevator_rad, double* dxdt, int& segment_hint) const {
    const double du = x[0], dw = x[1], q = x[2], dtheta = x[3], dh = x[4];
    const double height_m = start_height_m + dh;
    const double speed_mps = reference_speed_mps + du;
    const Segment& seg = SegmentFor(height_m, segment_hint);
    const double y = height_m - seg.reference_m;
    std::array<double, kReducedCount> r;
    for (int j = 0; j < kReducedCount; ++j) r[j] = seg.slope[j] * y + seg.value[j];
    // The products with the state do not need ρ or u; ρ(H) is computed alongside them and enters
    // last, so the dependent chain from the state to ẋ is u → u² → sums → ×ρ (about 45 cycles
    // rather than 60 with ρ·u formed first; measured 197 → 186 µs for the 30 s run).
    const double x_1 = r[kXu] * du + r[kXw] * dw;
    const double x_2 = r[kXh] * dh + r[kXde] * elevator_rad;
    const double z_1 = r[kZu] * du + r[kZw] * dw;
    const double z_2 = r[kZh] * dh + r[kZde] * elevator_rad;
    const double m_1 = (r[kMu] * du + r[kMw] * dw) + r[kMq] * q;
    const double m_2 = r[kMh] * dh + r[kMde] * elevator_rad;
    const double rho = density_.At(height_m);
    const double mw_dot = rho * r[kMwDot];
    const double u2 = speed_mps * speed_mps;
    const double w_dot = rho * (speed_mps * z_1 + u2 * z_2) + reference_speed_mps * q;
    dxdt[0] = rho * (speed_mps * x_1 + u2 * x_2) - kGravity_mps2 * dtheta;
    dxdt[1] = w_dot;
    dxdt[2] = rho * (speed_mps * m_1 + u2 * m_2) + mw_dot * w_dot;
    dxdt[3] = q;
    dxdt[4] = reference_speed_mps * dtheta - dw;
  }

  /// What Equation1Lanes reads from the lanes' tables, as chunks (defined below).
  template <class Arch, class V>
  struct LanesGathered;

  /// Equation1 for the lanes of one chunk on architecture Arch (lanes.h): lane i is
  /// tables[i]->Equation1(start_height_m[i], reference_speed_mps[i], x_i, elevator_i, dxdt_i,
  /// segment_hints[i]) bit for bit, with the same operations in the same order; the segment and the density's
  /// band are found per lane, the rest runs on the chunk. x[c], dxdt[c]: component c of the chunk's lanes.
  /// gathered: the lanes' table values of an earlier call with the same tables, or default-constructed.
  template <class Arch, class V>
  GESWEEP_ALWAYS_INLINE static void Equation1Lanes(const LinearDerivativeTable* const* tables,
                                                   const double* start_height_m,
                                                   const double* reference_speed_mps, const V* x,
                                                   const V& elevator_rad, V* dxdt, int* segment_hints,
                                                   LanesGathered<Arch, V>& gathered) {
    constexpr int kWidth = lanes::kChunkWidth<V>;
    const V du = x[0], dw = x[1], q = x[2], dtheta = x[3], dh = x[4];
    const V u0 = lanes::Load<Arch, V>(reference_speed_mps);
    const V height_m = lanes::Load<Arch, V>(start_height_m) + dh;
    const V speed_mps = u0 + du;
    alignas(64) double height[kWidth];
    lanes::Store<Arch>(height_m, height);
    const DensityPolynomial* density[kWidth];
    GatherSegments(tables, height, segment_hints, gathered, density);
    const V y = height_m - gathered.reference_m;
    auto r = [&](int j) { return gathered.slope[j] * y + gathered.value[j]; };
    const V x_1 = r(kXu) * du + r(kXw) * dw;
    const V x_2 = r(kXh) * dh + r(kXde) * elevator_rad;
    const V z_1 = r(kZu) * du + r(kZw) * dw;
    const V z_2 = r(kZh) * dh + r(kZde) * elevator_rad;
    const V m_1 = (r(kMu) * du + r(kMw) * dw) + r(kMq) * q;
    const V m_2 = r(kMh) * dh + r(kMde) * elevator_rad;
    const V rho = DensityPolynomial::AtLanes<Arch, V>(density, height_m, height, gathered.density_center_m,
                                                      gathered.density_coefficients);
    const V mw_dot = rho * r(kMwDot);
    const V u2 = speed_mps * speed_mps;
    const V w_dot = rho * (speed_mps * z_1 + u2 * z_2) + u0 * q;
    dxdt[0] = rho * (speed_mps * x_1 + u2 * x_2) - V(kGravity_mps2) * dtheta;
    dxdt[1] = w_dot;
    dxdt[2] = rho * (speed_mps * m_1 + u2 * m_2) + mw_dot * w_dot;
    dxdt[3] = q;
    dxdt[4] = u0 * dtheta - dw;
  }

  /// DerivativesAt for the lanes of one chunk on architecture Arch (lanes.h): derivative j of lane i
  /// (in the order of Reduced, below: Xu, Xw, Xh, Xδe, Zu, Zw, Zh, Zδe, Mu, Mw, Mq, Mh, Mδe, Mẇ) is
  /// that of tables[i]->DerivativesAt(height[i], speed[i], segment_hints[i]) bit for bit, with the same
  /// operations in the same order. height: the chunk's heights as doubles (the same as height_m).
  /// gathered as for Equation1Lanes.
  template <class Arch, class V>
  GESWEEP_ALWAYS_INLINE static void DerivativesLanes(const LinearDerivativeTable* const* tables,
                                                     const V& height_m, const double* height,
                                                     const V& speed_mps, int* segment_hints,
                                                     LanesGathered<Arch, V>& gathered, V* derivatives) {
    constexpr int kWidth = lanes::kChunkWidth<V>;
    const DensityPolynomial* density[kWidth];
    GatherSegments(tables, height, segment_hints, gathered, density);
    const V y = height_m - gathered.reference_m;
    V r[kReducedCount];
    for (int j = 0; j < kReducedCount; ++j) r[j] = gathered.slope[j] * y + gathered.value[j];
    const V rho = DensityPolynomial::AtLanes<Arch, V>(density, height_m, height, gathered.density_center_m,
                                                      gathered.density_coefficients);
    const V rho_u = rho * speed_mps;
    const V rho_u2 = rho_u * speed_mps;
    derivatives[kXu] = rho_u * r[kXu];
    derivatives[kXw] = rho_u * r[kXw];
    derivatives[kXh] = rho_u2 * r[kXh];
    derivatives[kXde] = rho_u2 * r[kXde];
    derivatives[kZu] = rho_u * r[kZu];
    derivatives[kZw] = rho_u * r[kZw];
    derivatives[kZh] = rho_u2 * r[kZh];
    derivatives[kZde] = rho_u2 * r[kZde];
    derivatives[kMu] = rho_u * r[kMu];
    derivatives[kMw] = rho_u * r[kMw];
    derivatives[kMq] = rho_u * r[kMq];
    derivatives[kMh] = rho_u2 * r[kMh];
    derivatives[kMde] = rho_u2 * r[kMde];
    derivatives[kMwDot] = rho * r[kMwDot];
  }

  /// Number of segments: one below the first row, one per pair of rows, one above the last.
  int segment_count() const { return static_cast<int>(segments_.size()); }

 public:
  /// The derivatives per segment, divided by their speed and density factors (DerivativesLanes' order).
  enum Reduced : int {
    kXu,
    kXw,
    kXh,
    kXde,
    kZu,
    kZw,
    kZh,
    kZde,
    kMu,
    kMw,
    kMq,
    kMh,
    kMde,
    kMwDot,
    kReducedCount
  };

 private:
  /// One segment (low, high]: R(H) = value + slope·(H − reference).
  struct Segment {
    std::array<double, kReducedCount> value{};
    std::array<double, kReducedCount> slope{};
    double reference_m = 0;
    double low_m = 0;
    double high_m = 0;
  };
  int Locate(double height_m, int start) const;

 public:
  /// What Equation1Lanes reads from the lanes' tables, as chunks: each lane's segment (R's values and
  /// slopes, the reference height) and density polynomial. Gathered on the first call and again only
  /// when a lane's segment is not the one they came from, so that the calls of one step, which
  /// almost always stay in their segments, gather once. Valid while the lanes' tables are.
  template <class Arch, class V>
  struct LanesGathered {
    const Segment* segment[lanes::kChunkWidth<V>] = {};
    V reference_m, slope[kReducedCount], value[kReducedCount];
    V density_center_m, density_coefficients[DensityPolynomial::kDegree + 1];
  };

  /// A kernel's loop over the chunks of its W lanes (lanes::Chunk<Arch, W>): body(k, gathered) for
  /// each chunk, k its first lane and `gathered` its table values kept in the arrays `a` from one
  /// call to the next (lanes::KeptChunks).
  template <class Arch, int W, class Arrays, class Body>
  GESWEEP_ALWAYS_INLINE static void ForEachChunk(Arrays& a, Body&& body) {
    using V = lanes::Chunk<Arch, W>;
    constexpr int kWidth = lanes::kChunkWidth<V>;
    LanesGathered<Arch, V>* kept = lanes::KeptChunks<LanesGathered<Arch, V>, W / kWidth>(a);
    for (int k = 0; k < W; k += kWidth) body(k, kept[k / kWidth]);
  }

 private:
  GESWEEP_ALWAYS_INLINE const Segment& SegmentFor(double height_m, int& segment_hint) const {
    int s = segment_hint;
    if (!(height_m > segments_[s].low_m && height_m <= segments_[s].high_m)) s = Locate(height_m, s);
    segment_hint = s;
    return segments_[s];
  }
  static std::array<double, kReducedCount> Reduce(const DimensionalDerivatives& d);
  // The segments of one chunk's lanes at their heights (each table's SegmentFor, with its hint),
  // gathered into `gathered` unless they are the ones already there; `density` gets each lane's
  // density polynomial.
  template <class Arch, class V>
  GESWEEP_ALWAYS_INLINE static void GatherSegments(const LinearDerivativeTable* const* tables,
                                                   const double* height, int* segment_hints,
                                                   LanesGathered<Arch, V>& gathered,
                                                   const DensityPolynomial** density) {
    constexpr int kWidth = lanes::kChunkWidth<V>;
    const Segment* seg[kWidth];
    bool same = true;
    for (int i = 0; i < kWidth; ++i) {
      seg[i] = &tables[i]->SegmentFor(height[i], segment_hints[i]);
      density[i] = &tables[i]->density_;
      same = same && seg[i] == gathered.segment[i];
    }
    if (!same) Gather(seg, density, gathered);
  }

  // The lanes' segments and polynomials as chunks (out of line: taken a few times per run).
  template <class Arch, class V>
  [[gnu::noinline]] static void Gather(const Segment* const* seg, const DensityPolynomial* const* density,
                                       LanesGathered<Arch, V>& gathered) {
    for (int i = 0; i < lanes::kChunkWidth<V>; ++i) gathered.segment[i] = seg[i];
    gathered.reference_m = lanes::Gather<Arch, V>([&](int i) { return seg[i]->reference_m; });
    for (int j = 0; j < kReducedCount; ++j) {
      gathered.slope[j] = lanes::Gather<Arch, V>([&](int i) { return seg[i]->slope[j]; });
      gathered.value[j] = lanes::Gather<Arch, V>([&](int i) { return seg[i]->value[j]; });
    }
    DensityPolynomial::GatherLanes<Arch, V>(density, gathered.density_center_m,
                                            gathered.density_coefficients);
  }

  std::vector<Segment> segments_;
  DensityPolynomial density_;
};

}  // namespace gesweep
