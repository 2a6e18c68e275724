#pragma once
/// The arithmetic of the open loop's lanes (SimulateOpenLoopBatch, open_loop.cc), compiled once per
/// instruction set: the RK4 stages of one step of W lanes and Eq. (1)'s right-hand side on them. The
/// definitions are in open_loop_lanes_kernel.h, instantiated for xsimd::sse2, xsimd::avx2 and
/// xsimd::avx512f in open_loop_lanes_sse2.cc, _avx2.cc and _avx512.cc, each built with its own -m
/// flags (engine/simulation/CMakeLists.txt); this header declares them for the generic code, which
/// calls the one KernelsFor<OpenLoopKernels, W> picks and never instantiates them itself.

#include "engine/simulation/lanes_isa.h"

namespace gesweep {

class LinearDerivativeTable;

namespace lanes {

/// What the kernels read and write for W lanes: component c of lane i at [c][i].
template <int W>
struct StepArrays {
  alignas(64) double x[5][W]{};             ///< the state at the step's start
  alignas(64) double f[5][W]{};             ///< the derivative there
  alignas(64) double x_new[5][W]{};         ///< Rk4Stages: the state at the step's end
  alignas(64) double f_new[5][W]{};         ///< Rk4Stages: the derivative there
  alignas(64) double t[W]{}, t_to[W]{};     ///< the step's start and end, s
  alignas(64) double elevator[W]{};         ///< δe over the step, rad
  alignas(64) double h0[W]{}, u0[W]{};      ///< each lane's H0 (m) and u0 (m/s)
  const LinearDerivativeTable* table[W]{};  ///< each lane's table (never null)
  int hint[W]{};                            ///< each lane's segment hint

  /// The kernels' table values of the lanes' segments, kept across steps (lanes::KeptChunks); the
  /// generic code never reads them.
  alignas(64) unsigned char gathered[kGatheredBytesPerLane * W]{};
  bool gathered_made = false;
};

/// The open loop's kernels (definitions in open_loop_lanes_kernel.h; KernelsFor<OpenLoopKernels, W>
/// picks an instruction set's).
struct OpenLoopKernels {
  template <int W>
  using Arrays = StepArrays<W>;

  /// Rk4Method::Advance's stages for every lane: from x, f, t, t_to and elevator, x_new
  /// and f_new = ẋ(x_new), lane i bit for bit what the scalar step of that lane's run computes.
  template <class Arch, int W>
  static void Rk4Stages(StepArrays<W>& lanes);

  /// f = ẋ(x) for every lane: lane i is table[i]->Equation1(h0[i], u0[i], x_i, elevator[i], f_i,
  /// hint[i]) bit for bit.
  template <class Arch, int W>
  static void Derivatives(StepArrays<W>& lanes);
};

}  // namespace lanes
}  // namespace gesweep
