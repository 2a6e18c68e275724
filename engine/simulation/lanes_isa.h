#pragma once
/// The instruction set the lanes of a batch compute with (docs/performance.md, "Batched time
/// responses"; lanes.h). The build is generic x86-64; the lanes' arithmetic is compiled once per
/// instruction set, each in a translation unit of its own (open_loop_lanes_<isa>.cc), and chosen at
/// run time by what the CPU has. Every choice gives the same results bit for bit: only the speed differs.

#include <optional>
#include <string>
#include <vector>

#include "engine/common/enum_names.h"

namespace gesweep {

/// The instruction sets of the lanes, all without fused multiply-add.
enum class LanesIsa {
  kSse2,    ///< 2 doubles per vector: every x86-64 CPU (the generic build's own)
  kAvx2,    ///< 4 doubles per vector (-mavx2)
  kAvx512,  ///< 8 doubles per vector (-mavx512f -mavx512dq -mavx512vl)
};

/// The values of GESWEEP_LANES_ISA: "sse2", "avx2", "avx512".
GESWEEP_ENUM_NAMES(LanesIsa, {kSse2, "sse2"}, {kAvx2, "avx2"}, {kAvx512, "avx512"});

/// The environment variable that forces the instruction set of every batch (unset or empty: chosen
/// by the CPU and the width, ChooseLanesIsa).
inline constexpr const char* kLanesIsaVariable = "GESWEEP_LANES_ISA";

/// Doubles per vector of `isa`: 2, 4 or 8.
int LanesIsaVectorWidth(LanesIsa isa);

/// Whether this CPU (and its operating system, which must save the wider registers) runs `isa`.
bool LanesIsaSupported(LanesIsa isa);

/// The instruction sets this CPU runs, narrowest first (always starts with kSse2).
std::vector<LanesIsa> SupportedLanesIsas();

/// The instruction set of a batch of `width` lanes: the one GESWEEP_LANES_ISA names when it is set,
/// else the widest this CPU runs whose vector fits in the width (width 1 and 2: sse2; 4: avx2; 8:
/// avx512), since a narrower width than the vector's computes on plain doubles. Throws
/// InputError("environment", "GESWEEP_LANES_ISA", ...) when the variable names no instruction set, or
/// one this CPU lacks.
LanesIsa ChooseLanesIsa(int width);

namespace lanes {

/// The kernels of one kind of lane (OpenLoopKernels, LandingKernels) for one instruction set and W
/// lanes: the RK4 stages of a step of every lane, and the derivatives at the lanes' states. Arrays is
/// the kind's arrays of W lanes (StepArrays<W>, LandingStepArrays<W>).
template <class Arrays>
struct RkKernels {
  void (*rk4_stages)(Arrays&) = nullptr;
  void (*derivatives)(Arrays&) = nullptr;
};

/// Bytes per lane of a kind's arrays' `gathered` storage: where the kernels keep their chunks'
/// gathered table values across calls (KeptChunks, lanes.h).
inline constexpr int kGatheredBytesPerLane = 384;

/// The kernels of Kind for W lanes on `isa`. Defined in lanes.h and instantiated for each kind and
/// width in the kind's dispatch file (GESWEEP_INSTANTIATE_KERNELS_FOR), which names each instruction
/// set's kernels without instantiating them. Precondition: LanesIsaSupported(isa) (GESWEEP_DEMAND).
template <class Kind, int W>
RkKernels<typename Kind::template Arrays<W>> KernelsFor(LanesIsa isa);

}  // namespace lanes
}  // namespace gesweep
