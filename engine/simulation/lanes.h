#pragma once
/// Lanes of a batch (docs/performance.md, "Batched time responses"): W runs integrated in lockstep
/// keep each state component as W doubles side by side, and the arithmetic on them goes through
/// xsimd's batch<double> (Debian's libxsimd-dev) in chunks of its hardware width, or through plain
/// doubles when W is not a multiple of it. Every operation is the same IEEE operation, in the same
/// order, as the scalar code it mirrors: no fused multiply-add (the build has no FMA, and
/// -ffp-contract=off keeps the compiler from forming one), no vector exp or pow. So a lane's result
/// does not depend on the width, on the other lanes, or on the instruction set, bit for bit.

#include <xsimd/xsimd.hpp>

namespace gesweep::lanes {

/// The hardware vector of doubles of this build (SSE2: 2 lanes, AVX2: 4, AVX-512: 8).
using HardwareVector = xsimd::batch<double>;
inline constexpr int kHardwareWidth = static_cast<int>(HardwareVector::size);

/// The chunk type for W lanes: the hardware vector when W is a multiple of its width, else double.
template <int W>
using Chunk = std::conditional_t<W % kHardwareWidth == 0, HardwareVector, double>;

/// Lanes in one chunk of type V.
template <class V>
inline constexpr int kChunkWidth = std::is_same_v<V, double> ? 1 : kHardwareWidth;

template <class V>
[[gnu::always_inline]] inline V Load(const double* p) {
  if constexpr (std::is_same_v<V, double>) {
    return *p;
  } else {
    return V::load_unaligned(p);
  }
}

template <class V>
[[gnu::always_inline]] inline void Store(const V& v, double* p) {
  if constexpr (std::is_same_v<V, double>) {
    *p = v;
  } else {
    v.store_unaligned(p);
  }
}

/// The chunk whose lane i is value(i).
template <class V, class F>
[[gnu::always_inline]] inline V Gather(F&& value) {
  alignas(64) double lanes[kChunkWidth<V>];
  for (int i = 0; i < kChunkWidth<V>; ++i) lanes[i] = value(i);
  return Load<V>(lanes);
}

}  // namespace gesweep::lanes
