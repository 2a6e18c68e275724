#pragma once
/// Lanes of a batch (docs/performance.md, "Batched time responses"): W runs integrated in lockstep
/// keep each state component as W doubles side by side, and the arithmetic on them goes through
/// xsimd's batch<double, Arch> (Debian's libxsimd-dev) in chunks of the architecture's width, or
/// through plain doubles when W is not a multiple of it. Every operation is the same IEEE operation,
/// in the same order, as the scalar code it mirrors: no fused multiply-add (the lanes' translation
/// units are built without FMA and with -ffp-contract=off), no vector exp or pow. So a lane's result
/// does not depend on the width, on the other lanes, or on the instruction set, bit for bit.
///
/// Every template here takes the architecture (xsimd::sse2, xsimd::avx2, xsimd::avx512f) as its first
/// parameter, also where the chunk is a plain double: the code of each architecture is compiled in a
/// translation unit of its own, with its own -m flags (open_loop_lanes_<isa>.cc), and the architecture
/// in every instantiation's name keeps the linker from merging one architecture's copy into
/// another's. Only those translation units instantiate these templates (open_loop_lanes_kernel.h).

#include <new>
#include <type_traits>
#include <xsimd/xsimd.hpp>

#include "engine/common/errors.h"
#include "engine/simulation/lanes_isa.h"

namespace gesweep::lanes {

/// The vector of doubles of architecture Arch (xsimd::sse2: 2 lanes, xsimd::avx2: 4, xsimd::avx512f: 8).
template <class Arch>
using Vector = xsimd::batch<double, Arch>;
template <class Arch>
inline constexpr int kVectorWidth = static_cast<int>(Vector<Arch>::size);

/// The chunk type for W lanes on Arch: its vector when W is a multiple of its width, else double.
template <class Arch, int W>
using Chunk = std::conditional_t<W % kVectorWidth<Arch> == 0, Vector<Arch>, double>;

/// Lanes in one chunk of type V.
template <class V>
inline constexpr int kChunkWidth = 1;
template <class Arch>
inline constexpr int kChunkWidth<Vector<Arch>> = kVectorWidth<Arch>;

template <class Arch, class V>
[[gnu::always_inline]] inline V Load(const double* p) {
  if constexpr (std::is_same_v<V, double>) {
    return *p;
  } else {
    static_assert(std::is_same_v<V, Vector<Arch>>);
    return V::load_unaligned(p);
  }
}

template <class Arch, class V>
[[gnu::always_inline]] inline void Store(const V& v, double* p) {
  if constexpr (std::is_same_v<V, double>) {
    *p = v;
  } else {
    static_assert(std::is_same_v<V, Vector<Arch>>);
    v.store_unaligned(p);
  }
}

/// The chunk whose lane i is value(i).
template <class Arch, class V, class F>
[[gnu::always_inline]] inline V Gather(F&& value) {
  alignas(64) double lanes[kChunkWidth<V>];
  for (int i = 0; i < kChunkWidth<V>; ++i) lanes[i] = value(i);
  return Load<Arch, V>(lanes);
}

/// The kernels' per-chunk objects of type T (a LinearDerivativeTable::LanesGathered: the chunk's
/// gathered table values), kept in the arrays' storage `a.gathered` from one kernel call to the next
/// and made, value-initialised, by the first (`a.gathered_made`). Entry c is chunk c's. Whatever a
/// kept object holds is valid while the lanes' tables are: it says which segments it came from.
template <class T, int kChunks, class Arrays>
[[gnu::always_inline]] inline T* KeptChunks(Arrays& a) {
  static_assert(sizeof(T) * kChunks <= sizeof(a.gathered) && alignof(T) <= 64 &&
                std::is_trivially_destructible_v<T>);
  if (!a.gathered_made) {
    for (int c = 0; c < kChunks; ++c) new (a.gathered + c * sizeof(T)) T();
    a.gathered_made = true;
  }
  return std::launder(reinterpret_cast<T*>(a.gathered));
}

/// `pick.template operator()<Arch>()` for the xsimd architecture of `isa`: the kernels of one
/// instruction set, named (not instantiated) by the generic dispatch code (open_loop_lanes.cc,
/// control/landing_lanes.cc); each instance is made in its instruction set's own translation unit.
/// Precondition: LanesIsaSupported(isa) (GESWEEP_DEMAND).
template <class Pick>
auto PickForIsa(LanesIsa isa, const Pick& pick) {
  GESWEEP_DEMAND(LanesIsaSupported(isa));
  switch (isa) {
    case LanesIsa::kSse2:
      return pick.template operator()<xsimd::sse2>();
    case LanesIsa::kAvx2:
      return pick.template operator()<xsimd::avx2>();
    case LanesIsa::kAvx512:
      return pick.template operator()<xsimd::avx512f>();
  }
  GESWEEP_UNREACHABLE();
}

template <class Kind, int W>
RkKernels<typename Kind::template Arrays<W>> KernelsFor(LanesIsa isa) {
  return PickForIsa(isa, []<class Arch>() {
    return RkKernels<typename Kind::template Arrays<W>>{&Kind::template Rk4Stages<Arch, W>,
                                                        &Kind::template Derivatives<Arch, W>};
  });
}

}  // namespace gesweep::lanes

/// Instantiates KernelsFor<KIND, W> (the dispatch of KIND's kernels) for the widths 1, 2, 4 and 8.
#define GESWEEP_INSTANTIATE_KERNELS_FOR(KIND)                                              \
  template gesweep::lanes::RkKernels<KIND::Arrays<1>> gesweep::lanes::KernelsFor<KIND, 1>( \
      gesweep::LanesIsa);                                                                  \
  template gesweep::lanes::RkKernels<KIND::Arrays<2>> gesweep::lanes::KernelsFor<KIND, 2>( \
      gesweep::LanesIsa);                                                                  \
  template gesweep::lanes::RkKernels<KIND::Arrays<4>> gesweep::lanes::KernelsFor<KIND, 4>( \
      gesweep::LanesIsa);                                                                  \
  template gesweep::lanes::RkKernels<KIND::Arrays<8>> gesweep::lanes::KernelsFor<KIND, 8>( \
      gesweep::LanesIsa);                                                                  \
  static_assert(true)

/// Instantiates KIND's kernels (Rk4Stages, Derivatives) of architecture ARCH for the widths 1, 2, 4
/// and 8, in ARCH's own translation unit.
#define GESWEEP_INSTANTIATE_RK_KERNELS(KIND, ARCH)            \
  template void KIND::Rk4Stages<ARCH, 1>(KIND::Arrays<1>&);   \
  template void KIND::Rk4Stages<ARCH, 2>(KIND::Arrays<2>&);   \
  template void KIND::Rk4Stages<ARCH, 4>(KIND::Arrays<4>&);   \
  template void KIND::Rk4Stages<ARCH, 8>(KIND::Arrays<8>&);   \
  template void KIND::Derivatives<ARCH, 1>(KIND::Arrays<1>&); \
  template void KIND::Derivatives<ARCH, 2>(KIND::Arrays<2>&); \
  template void KIND::Derivatives<ARCH, 4>(KIND::Arrays<4>&); \
  template void KIND::Derivatives<ARCH, 8>(KIND::Arrays<8>&); \
  static_assert(true)
