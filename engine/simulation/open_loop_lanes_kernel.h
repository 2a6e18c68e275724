#pragma once
/// The definitions of open_loop_lanes.h's kernels. Included only by open_loop_lanes_<isa>.cc, each
/// of which instantiates them for its architecture under its own -m flags: a translation unit that
/// includes this header and instantiates a kernel for an architecture it is not built for breaks the
/// rule that keeps the architectures apart (lanes.h).

#include "engine/simulation/derivative_table.h"
#include "engine/simulation/lanes.h"
#include "engine/simulation/open_loop_lanes.h"

namespace gesweep::lanes {

// Eq. (1) on the chunk of lanes [k, k + width of V) of `a`: its tables, start and reference values and
// hints; gathered: the chunk's table values of an earlier call of this step, or default-constructed.
template <class Arch, class V, int W>
[[gnu::always_inline]] inline void ChunkDerivative(StepArrays<W>& a, int k, const V* x, const V& elevator,
                                                   V* dxdt,
                                                   LinearDerivativeTable::LanesGathered<Arch, V>& gathered) {
  LinearDerivativeTable::Equation1Lanes<Arch, V>(&a.table[k], &a.h0[k], &a.u0[k], x, elevator, dxdt,
                                                 &a.hint[k], gathered);
}

template <class Arch, int W>
void OpenLoopKernels::Rk4Stages(StepArrays<W>& a) {
  using V = Chunk<Arch, W>;
  LinearDerivativeTable::ForEachChunk<Arch, W>(a, [&](int k, auto& gathered) GESWEEP_ALWAYS_INLINE_LAMBDA {
    V x[5], f[5], stage[5], k2[5], k3[5], k4[5], x_new[5], f_new[5];
    for (int c = 0; c < 5; ++c) {
      x[c] = Load<Arch, V>(&a.x[c][k]);
      f[c] = Load<Arch, V>(&a.f[c][k]);
    }
    // Rk4Method::Advance's step, h/2 and h/6, as it computes them.
    const V h = Load<Arch, V>(&a.t_to[k]) - Load<Arch, V>(&a.t[k]);
    const V half_h = V(0.5) * h;
    const V sixth_h = h / V(6.0);
    const V elevator = Load<Arch, V>(&a.elevator[k]);
    // Rk4Method::Advance's arithmetic, in its order.
    for (int c = 0; c < 5; ++c) stage[c] = x[c] + half_h * f[c];
    ChunkDerivative<Arch>(a, k, stage, elevator, k2, gathered);
    for (int c = 0; c < 5; ++c) stage[c] = x[c] + half_h * k2[c];
    ChunkDerivative<Arch>(a, k, stage, elevator, k3, gathered);
    for (int c = 0; c < 5; ++c) stage[c] = x[c] + h * k3[c];
    ChunkDerivative<Arch>(a, k, stage, elevator, k4, gathered);
    for (int c = 0; c < 5; ++c) x_new[c] = x[c] + sixth_h * ((f[c] + k4[c]) + V(2.0) * (k2[c] + k3[c]));
    ChunkDerivative<Arch>(a, k, x_new, elevator, f_new, gathered);
    for (int c = 0; c < 5; ++c) {
      Store<Arch>(x_new[c], &a.x_new[c][k]);
      Store<Arch>(f_new[c], &a.f_new[c][k]);
    }
  });
}

template <class Arch, int W>
void OpenLoopKernels::Derivatives(StepArrays<W>& a) {
  using V = Chunk<Arch, W>;
  LinearDerivativeTable::ForEachChunk<Arch, W>(a, [&](int k, auto& gathered) GESWEEP_ALWAYS_INLINE_LAMBDA {
    V x[5], f[5];
    for (int c = 0; c < 5; ++c) x[c] = Load<Arch, V>(&a.x[c][k]);
    ChunkDerivative<Arch>(a, k, x, Load<Arch, V>(&a.elevator[k]), f, gathered);
    for (int c = 0; c < 5; ++c) Store<Arch>(f[c], &a.f[c][k]);
  });
}

}  // namespace gesweep::lanes
