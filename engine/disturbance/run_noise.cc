#include "engine/disturbance/run_noise.h"

#include <cmath>
#include <numbers>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

constexpr std::uint64_t kSeedDomain =
    0x6765737765657021ULL;  // "gesweep!": separates from other uses of the seed
constexpr int kStreamCount = 4;

constexpr std::uint64_t Hash(std::uint64_t key, std::uint64_t counter) {
  return SplitMix64Mix(key ^ SplitMix64Mix(counter + 1));
}

}  // namespace

RunNoise::RunNoise(std::uint64_t study_seed, std::uint64_t run_index)
    : key_(Hash(SplitMix64Mix(study_seed ^ kSeedDomain), run_index)) {}

RunNoise::RunNoise(std::span<const double> point) : point_(point) { GESWEEP_DEMAND(!point.empty()); }

double RunNoise::Uniform(std::uint64_t counter) const {
  return static_cast<double>((Hash(key_, counter) >> 11) + 1) * 0x1.0p-53;
}

double RunNoise::StandardNormal(NoiseStream stream, std::uint64_t sample_index) const {
  if (!point_.empty()) {
    const std::uint64_t i = NoisePointIndex(stream, sample_index);
    GESWEEP_DEMAND(i < point_.size());
    return point_[i];
  }
  const std::uint64_t counter = 2 * (kStreamCount * sample_index + static_cast<std::uint64_t>(stream));
  const double u1 = Uniform(counter);  // (0, 1]: the log is finite
  const double u2 = Uniform(counter + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace gesweep
