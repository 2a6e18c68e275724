#pragma once
/// Small, portable, deterministic hashes: run ids, study fingerprints and the counter-based random
/// streams of the lazy designs. Nothing here depends on the platform's std::hash or on the standard
/// library's distributions, so every machine computes the same numbers.

#include <cstdint>
#include <cstring>
#include <string_view>

namespace gesweep {

/// FNV-1a, 64 bits, over bytes, continuing from `state` (start with kFnvOffset).
inline constexpr std::uint64_t kFnvOffset = 0xcbf29ce484222325ULL;
inline std::uint64_t Fnv1a64(std::string_view bytes, std::uint64_t state = kFnvOffset) {
  for (unsigned char c : bytes) {
    state ^= c;
    state *= 0x100000001b3ULL;
  }
  return state;
}

/// Feeds the bit pattern of a double into an FNV-1a state.
inline std::uint64_t Fnv1a64(double value, std::uint64_t state) {
  char bytes[sizeof(double)];
  std::memcpy(bytes, &value, sizeof(double));
  return Fnv1a64(std::string_view(bytes, sizeof(double)), state);
}

/// SplitMix64's finaliser: a bijective 64-bit mixer (Steele, Lea, Flood 2014).
inline constexpr std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// A hash of several 64-bit words (order matters).
inline constexpr std::uint64_t HashWords(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0,
                                         std::uint64_t d = 0) {
  return Mix64(Mix64(Mix64(Mix64(a) ^ b) ^ c) ^ d);
}

/// A uniform double in [0, 1) from 64 random bits (53 significant bits).
inline constexpr double UnitInterval(std::uint64_t bits) {
  return static_cast<double>(bits >> 11) * 0x1.0p-53;
}

/// A counter-based random stream: SplitMix64 seeded by a key. Portable and cheap to create, so a
/// lazy design can draw the numbers of any run or trajectory on its own.
class SplitMixStream {
 public:
  explicit SplitMixStream(std::uint64_t key) : state_(key) {}
  std::uint64_t Next() {
    state_ += 0x9e3779b97f4a7c15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  /// A uniform integer in [0, n), n ≥ 1, without modulo bias (rejection).
  std::uint64_t Below(std::uint64_t n) {
    const std::uint64_t limit = ~std::uint64_t{0} - (~std::uint64_t{0} % n);
    std::uint64_t x;
    do {
      x = Next();
    } while (x >= limit);
    return x % n;
  }

 private:
  std::uint64_t state_;
};

}  // namespace gesweep
