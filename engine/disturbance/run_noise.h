#pragma once
/// Randomness as data (docs/model.md §9, docs/disturbance.md): the white noise of one run, a pure
/// function of (study seed, run index, stream, sample index). Nothing is stateful, so the noise does
/// not depend on threads, shards, ranks, the order of calls or the integrator's steps, and any
/// sample of any run can be recomputed alone.
///
/// Construction (counter-based, SplitMix-style):
///   Mix(z)         = the SplitMix64 finaliser (Steele, Lea & Flood 2014; Vigna's splitmix64.c):
///                    z ^= z>>30; z *= 0xbf58476d1ce4e5b9; z ^= z>>27; z *= 0x94d049bb133111eb; z ^= z>>31
///   Hash(k, c)     = Mix(k ^ Mix(c + 1))       (a bijection of c for each key k)
///   run key        = Hash(Mix(study seed ^ 0x6765737765657021), run index)
///   uniform c      = ((Hash(run key, c) >> 11) + 1)·2⁻⁵³ in (0, 1]
///   normal (s, k)  = Box–Muller cos branch of the uniforms c = 2(4k + s) and 2(4k + s) + 1
/// Mixing the counter before the XOR (rather than adding a Weyl increment, as SplitMix64 itself
/// does) keeps two runs' streams from being shifted copies of each other.

#include <cstdint>
#include <span>

namespace gesweep {

/// The SplitMix64 output finaliser (a bijection of 64-bit words).
constexpr std::uint64_t SplitMix64Mix(std::uint64_t z) {
  z ^= z >> 30;
  z *= 0xbf58476d1ce4e5b9ULL;
  z ^= z >> 27;
  z *= 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return z;
}

/// Streams of one run's noise (at most 4; each sample index k has one normal per stream).
enum class NoiseStream : int {
  kTurbulenceU = 0,   ///< drives the u forming filter
  kTurbulenceW = 1,   ///< drives the w forming filter
  kInitialState = 2,  ///< the filters' stationary initial states (sample indices 0, 1, 2)
};

/// The layout of a run's noise as a point u of a standard-normal space (the subset simulation's
/// coordinates, docs/dispersion.md): u[0..2] are the initial-state samples 0, 1, 2; the two
/// turbulence streams of sample k are u[3 + 2k] (kTurbulenceU) and u[3 + 2k + 1] (kTurbulenceW).
constexpr std::uint64_t NoisePointIndex(NoiseStream stream, std::uint64_t sample_index) {
  if (stream == NoiseStream::kInitialState) return sample_index;
  return 3 + 2 * sample_index + (stream == NoiseStream::kTurbulenceW ? 1 : 0);
}
/// The dimension of a point that holds the initial state and samples 0 .. sample_count - 1.
constexpr std::uint64_t NoisePointDimension(std::uint64_t sample_count) { return 3 + 2 * sample_count; }

/// One run's noise: the counter-based stream of (study seed, run index), or a given point u of the
/// standard-normal space in the layout of NoisePointIndex (a run of a subset simulation).
class RunNoise {
 public:
  RunNoise(std::uint64_t study_seed, std::uint64_t run_index);
  /// The noise is `point` (not copied: it must outlive this object). A sample past the point's end
  /// is a programming error (GESWEEP_DEMAND): the caller sizes the point for the run's whole time.
  explicit RunNoise(std::span<const double> point);

  /// The run key, a function of (study seed, run index) alone.
  std::uint64_t key() const { return key_; }
  /// The uniform of counter c, in (0, 1].
  double Uniform(std::uint64_t counter) const;
  /// A standard normal variate N(0, 1) for (stream, sample index k ≥ 0).
  double StandardNormal(NoiseStream stream, std::uint64_t sample_index) const;
  /// Whether the noise is a given point.
  bool from_point() const { return !point_.empty(); }

 private:
  std::uint64_t key_ = 0;
  std::span<const double> point_;
};

}  // namespace gesweep
