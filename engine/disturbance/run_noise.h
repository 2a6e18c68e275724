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

/// One run's noise.
class RunNoise {
 public:
  RunNoise(std::uint64_t study_seed, std::uint64_t run_index);

  /// The run key, a function of (study seed, run index) alone.
  std::uint64_t key() const { return key_; }
  /// The uniform of counter c, in (0, 1].
  double Uniform(std::uint64_t counter) const;
  /// A standard normal variate N(0, 1) for (stream, sample index k ≥ 0).
  double StandardNormal(NoiseStream stream, std::uint64_t sample_index) const;

 private:
  std::uint64_t key_;
};

}  // namespace gesweep
