#include "engine/rare/subset_simulation.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>

#include "engine/common/errors.h"
#include "engine/disturbance/run_noise.h"

namespace gesweep::rare {
namespace {

constexpr std::uint64_t kSeedDomain = 0x7375627365742d31ULL;  // "subset-1": not RunNoise's domain
constexpr std::uint64_t kPurposeNormal = 0;
constexpr std::uint64_t kPurposeUniform = 1;
constexpr std::uint64_t kSeedShuffleChain = 0xffffffffULL;  // a chain number no chain has (chains < 2^31)
constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kZ975 = 1.959963984540054;  // the standard normal's 0.975 quantile
constexpr int kMaxSamplesPerLevel = 10'000'000;
constexpr int kMaxLevels = 100;

constexpr std::uint64_t Hash(std::uint64_t key, std::uint64_t counter) {
  return SplitMix64Mix(key ^ SplitMix64Mix(counter + 1));
}

/// The random numbers of one (seed, level, chain, step): normals for the components and, for the
/// modified Metropolis, uniforms for their acceptance; each a pure function of its counter.
class Stream {
 public:
  Stream(std::uint64_t seed, int level, std::uint64_t chain, int step)
      : key_(Hash(Hash(Hash(SplitMix64Mix(seed ^ kSeedDomain), static_cast<std::uint64_t>(level)), chain),
                  static_cast<std::uint64_t>(step))) {}

  /// In (0, 1].
  double Uniform(std::uint64_t purpose, std::uint64_t counter) const {
    return static_cast<double>((Hash(Hash(key_, purpose), counter) >> 11) + 1) * 0x1.0p-53;
  }
  /// d standard normals, Box-Muller on the uniform pairs (2k, 2k + 1), both branches.
  void Normals(std::span<double> out) const {
    const std::uint64_t normal_key = Hash(key_, kPurposeNormal);
    const auto uniform = [&](std::uint64_t c) {
      return static_cast<double>((Hash(normal_key, c) >> 11) + 1) * 0x1.0p-53;
    };
    for (std::size_t k = 0; k < out.size(); k += 2) {
      const double radius = std::sqrt(-2.0 * std::log(uniform(k)));
      const double angle = kTwoPi * uniform(k + 1);
      out[k] = radius * std::cos(angle);
      if (k + 1 < out.size()) out[k + 1] = radius * std::sin(angle);
    }
  }

 private:
  std::uint64_t key_;
};

std::int64_t SeedCount(const SubsetOptions& options) {
  return std::llround(options.samples_per_level * options.level_probability);
}

/// A NaN is outside every event (as +infinity); -infinity and finite values are themselves.
double Ordered(double g) { return std::isnan(g) ? std::numeric_limits<double>::infinity() : g; }

/// The layout of one level's N samples: chain c holds positions [offset[c], offset[c] + length[c]).
struct ChainLayout {
  std::vector<std::int64_t> offset, length;
};

ChainLayout MakeLayout(std::int64_t n, std::int64_t chains) {
  ChainLayout layout;
  std::int64_t at = 0;
  for (std::int64_t c = 0; c < chains; ++c) {
    const std::int64_t length = n / chains + (c < n % chains ? 1 : 0);
    layout.offset.push_back(at);
    layout.length.push_back(length);
    at += length;
  }
  return layout;
}

/// gamma of Au & Beck (2001) for the indicator `hit` over the chains of `layout` with mean p,
/// generalised to chains of unequal length: gamma = (2 / N) sum_k rho(k) * (pairs at lag k).
double CorrelationFactor(const std::vector<char>& hit, const ChainLayout& layout, double p) {
  const double r0 = p * (1 - p);
  if (r0 <= 0) return 0;
  const std::int64_t longest = *std::max_element(layout.length.begin(), layout.length.end());
  const auto n = static_cast<double>(hit.size());
  double gamma = 0;
  for (std::int64_t lag = 1; lag < longest; ++lag) {
    std::int64_t pairs = 0, both = 0;
    for (std::size_t c = 0; c < layout.length.size(); ++c) {
      const std::int64_t start = layout.offset[c];
      for (std::int64_t t = 0; t + lag < layout.length[c]; ++t) {
        ++pairs;
        both += (hit[start + t] && hit[start + t + lag]) ? 1 : 0;
      }
    }
    if (pairs == 0) break;
    const double rho = (static_cast<double>(both) / static_cast<double>(pairs) - p * p) / r0;
    gamma += 2.0 * rho * static_cast<double>(pairs) / n;
  }
  return gamma;
}

/// delta_j for a level's fraction p of N samples (Au & Beck 2001, eq. for the Markov-chain level,
/// gamma = 0 at the Monte Carlo level). 1 + gamma is held at 0 or above.
double LevelCov(double p, std::int64_t n, double gamma) {
  if (p <= 0) return std::numeric_limits<double>::infinity();
  return std::sqrt((1 - p) / (static_cast<double>(n) * p) * std::max(0.0, 1 + gamma));
}

}  // namespace

void ValidateSubsetOptions(const SubsetOptions& options, const std::string& source) {
  const double p0 = options.level_probability;
  if (!(std::isfinite(p0) && p0 > 0 && p0 < 1)) {
    throw InputError(source, "level_probability", ShortNumber(p0), "a probability strictly between 0 and 1");
  }
  if (options.samples_per_level < 1 || options.samples_per_level > kMaxSamplesPerLevel) {
    throw InputError(source, "samples_per_level", std::to_string(options.samples_per_level),
                     "an integer from 1 to " + std::to_string(kMaxSamplesPerLevel));
  }
  const double seeds = options.samples_per_level * p0;
  const double rounded = std::round(seeds);
  if (std::abs(seeds - rounded) > 1e-9 * std::max(1.0, seeds) || rounded < 1 ||
      rounded >= options.samples_per_level) {
    throw InputError(source, "samples_per_level", std::to_string(options.samples_per_level),
                     "a number N of samples per level with N * level_probability (" + ShortNumber(p0) +
                         ") an integer from 1 to N - 1 (N * p0 = " + ShortNumber(seeds) + ")");
  }
  if (rounded < options.min_chains) {
    throw InputError(source, "samples_per_level", std::to_string(options.samples_per_level),
                     "at least " + std::to_string(options.min_chains) + " chains: N * level_probability >= " +
                         std::to_string(options.min_chains) + " (here " + ShortNumber(seeds) + ")");
  }
  if (options.max_levels < 1 || options.max_levels > kMaxLevels) {
    throw InputError(source, "max_levels", std::to_string(options.max_levels),
                     "an integer from 1 to " + std::to_string(kMaxLevels));
  }
  const auto& names = EnumNames<ConditionalSampler>::kTable;
  if (std::none_of(std::begin(names), std::end(names),
                   [&](const auto& entry) { return entry.value == options.sampler; })) {
    throw InputError(source, "sampler", std::to_string(static_cast<int>(options.sampler)),
                     EnumChoices<ConditionalSampler>());
  }
  if (!(std::isfinite(options.initial_scale) && options.initial_scale > 0 && options.initial_scale <= 1)) {
    throw InputError(source, "initial_scale", ShortNumber(options.initial_scale), "a number in (0, 1]");
  }
  if (!(std::isfinite(options.target_acceptance) && options.target_acceptance > 0 &&
        options.target_acceptance < 1)) {
    throw InputError(source, "target_acceptance", ShortNumber(options.target_acceptance),
                     "a number in (0, 1)");
  }
  if (options.adaptation_groups < 1 || options.adaptation_groups > rounded) {
    throw InputError(
        source, "adaptation_groups", std::to_string(options.adaptation_groups),
        "an integer from 1 to the number of chains N * level_probability (" + ShortNumber(rounded) + ")");
  }
}

LimitStateBatch ParallelLimitState(std::function<double(std::span<const double> u)> g) {
  return [g = std::move(g)](const PointBatch& batch, std::span<double> values) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, batch.size()),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) values[i] = g(batch.point(i));
                      });
  };
}

void LognormalInterval95(double p, double cov, double& low, double& high) {
  if (!(p > 0)) {
    low = high = 0;
    return;
  }
  if (!std::isfinite(cov)) {
    low = 0;
    high = std::numeric_limits<double>::infinity();
    return;
  }
  const double s2 = std::log1p(cov * cov);
  const double s = std::sqrt(s2);
  const double mean_log = std::log(p) - s2 / 2;
  low = std::exp(mean_log - kZ975 * s);
  high = std::exp(mean_log + kZ975 * s);
}

std::string SubsetResult::Summary() const {
  char text[320];
  std::snprintf(text, sizeof text,
                "P = %.4g, CoV %.3g (upper %.3g), 95%% [%.4g, %.4g], %zu levels, %lld evaluations",
                probability, coefficient_of_variation, coefficient_of_variation_upper, interval_95_low,
                interval_95_high, levels.size(), static_cast<long long>(evaluations));
  std::string line = text;
  if (failed_evaluations > 0) line += ", " + std::to_string(failed_evaluations) + " failed (NaN)";
  if (status == Status::kLevelCap) line += ", level cap reached: P < " + ShortNumber(upper_bound);
  return line;
}

namespace {

/// A sample's place in a level's order: by value (NaN as +infinity), ties by position in the level.
struct SampleKey {
  double g = 0;
  std::int64_t position = 0;
  EvaluationTag tag;          ///< the evaluation that gave the sample's point (not part of the order)
  std::int64_t ancestor = 0;  ///< the Monte Carlo sample the point descends from (not part of the order)
};
bool Before(const SampleKey& a, const SampleKey& b) {
  const double x = Ordered(a.g), y = Ordered(b.g);
  return x < y || (x == y && a.position < b.position);
}

/// The `capacity` samples of a level that come first in SampleKey order, with their points: the
/// seeds of the next level's chains. Offered the level's samples one by one (a bounded max-heap),
/// so a level holds capacity * d doubles of points, not N * d.
class SeedSelection {
 public:
  SeedSelection(std::int64_t capacity, std::size_t dimension)
      : capacity_(capacity), d_(dimension), points_(static_cast<std::size_t>(capacity) * dimension) {}
  void Clear() {
    keys_.clear();
    heap_.clear();
  }
  void Offer(const SampleKey& key, const double* point) {
    const auto later = [&](std::int64_t a, std::int64_t b) { return Before(keys_[a], keys_[b]); };
    std::int64_t slot;
    if (static_cast<std::int64_t>(heap_.size()) < capacity_) {
      slot = static_cast<std::int64_t>(keys_.size());
      keys_.push_back(key);
    } else {
      if (!Before(key, keys_[heap_.front()])) return;
      std::pop_heap(heap_.begin(), heap_.end(), later);
      slot = heap_.back();
      heap_.pop_back();
      keys_[slot] = key;
    }
    std::copy(point, point + d_, points_.begin() + slot * static_cast<std::int64_t>(d_));
    heap_.push_back(slot);
    std::push_heap(heap_.begin(), heap_.end(), later);
  }
  /// The slots in SampleKey order.
  std::vector<std::int64_t> Sorted() const {
    std::vector<std::int64_t> slots(heap_);
    std::sort(slots.begin(), slots.end(),
              [&](std::int64_t a, std::int64_t b) { return Before(keys_[a], keys_[b]); });
    return slots;
  }
  const SampleKey& key(std::int64_t slot) const { return keys_[slot]; }
  const double* point(std::int64_t slot) const {
    return points_.data() + slot * static_cast<std::int64_t>(d_);
  }

 private:
  std::int64_t capacity_;
  std::size_t d_;
  std::vector<double> points_;
  std::vector<SampleKey> keys_;
  std::vector<std::int64_t> heap_;
};

/// The failing samples (g <= 0) of a level, as they are met: their count, the sum of their points and
/// the one nearest the origin (the most likely under N(0, I); the first met among equals).
struct FailureRecord {
  std::int64_t count = 0;
  std::vector<double> sum;
  double nearest_norm2 = std::numeric_limits<double>::infinity();
  std::vector<double> nearest;
  EvaluationTag nearest_tag;
  double nearest_g = 0;
  void Reset(std::size_t d) {
    count = 0;
    sum.assign(d, 0.0);
    nearest_norm2 = std::numeric_limits<double>::infinity();
    nearest.clear();
  }
  void Offer(const double* point, std::size_t d, double g, const EvaluationTag& tag) {
    if (!(g <= 0)) return;
    ++count;
    double norm2 = 0;
    for (std::size_t k = 0; k < d; ++k) {
      sum[k] += point[k];
      norm2 += point[k] * point[k];
    }
    if (norm2 < nearest_norm2) {
      nearest_norm2 = norm2;
      nearest.assign(point, point + d);
      nearest_tag = tag;
      nearest_g = g;
    }
  }
};

/// The level a conditional step builds: its number, the threshold its samples stay at or below,
/// its chains' layout and its values g by position.
struct ChainLevel {
  int number = 0;
  double threshold = 0;
  ChainLayout layout;
  std::vector<double> g;
};

/// The level threshold of values g: the midpoint of the N_s-th and (N_s + 1)-th smallest (NaN as
/// +infinity), the N_s-th alone when the next is not finite. Fewer than N_s samples with a value (the
/// rest NaN): +infinity, and no conditional level can be formed (kTooManyFailedEvaluations).
double LevelThreshold(const std::vector<double>& g, std::int64_t ns) {
  std::vector<std::int64_t> order(g.size());
  std::iota(order.begin(), order.end(), std::int64_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::int64_t a, std::int64_t b) { return Ordered(g[a]) < Ordered(g[b]); });
  const double inner = Ordered(g[order[ns - 1]]), outer = Ordered(g[order[ns]]);
  return std::isfinite(outer) ? (inner + outer) / 2 : inner;
}

/// One subset simulation, stage by stage. Memory: the level's values (N), the seeds of the next level
/// and the chains' states (N_s points each) and one batch of candidates, whatever N: a level never
/// holds its N points.
class SubsetRun {
 public:
  SubsetRun(const LimitStateBatch& limit_state, int dimension, const SubsetOptions& options)
      : limit_state_(limit_state),
        dimension_(dimension),
        options_(options),
        n_(options.samples_per_level),
        ns_(SeedCount(options)),
        d_(static_cast<std::size_t>(dimension)),
        g_(static_cast<std::size_t>(n_)),
        selection_(ns_, d_),
        next_selection_(ns_, d_),
        lambda_(options.initial_scale),
        state_(static_cast<std::size_t>(ns_) * d_),
        state_tag_(static_cast<std::size_t>(ns_)),
        state_ancestor_(static_cast<std::size_t>(ns_)) {
    result_.dimension = dimension;
    failures_seen_.Reset(d_);
  }

  /// Level 1, then a conditional level after each level until N_s samples fail or the level cap.
  SubsetResult Run() {
    SampleMonteCarloLevel();
    for (int level = 1;; ++level) {
      SubsetLevel record = SampledRecord();
      const auto failures = std::count_if(g_.begin(), g_.end(), [](double v) { return v <= 0; });
      const bool last = failures >= ns_ || level == options_.max_levels;
      const double threshold = last ? 0 : LevelThreshold(g_, ns_);
      MeasureLevel(level, threshold, record);
      if (!std::isfinite(threshold)) {
        result_.status = SubsetResult::Status::kTooManyFailedEvaluations;
        result_.probability = std::numeric_limits<double>::quiet_NaN();
        break;
      }
      if (last) {
        Conclude(failures, record.conditional_probability);
        break;
      }
      product_ *= record.conditional_probability;
      const std::vector<std::int64_t> seeds = ShuffledSeeds(level);
      // Level + 1: N_s chains, chain c of length layout.length[c], its seed at step 0.
      ChainLevel next{level + 1, threshold, MakeLayout(n_, ns_), std::vector<double>(g_.size())};
      StartChains(next, seeds);
      RunChains(next);
      std::swap(selection_, next_selection_);
      g_.swap(next.g);
      layout_ = std::move(next.layout);
    }
    CombineLevels();
    return std::move(result_);
  }

 private:
  /// values_ = g at the batch candidates_ (tags batch_tags_); NaN where the limit state sets none.
  void Evaluate() {
    std::fill(values_.begin(), values_.end(), std::numeric_limits<double>::quiet_NaN());
    limit_state_(PointBatch{candidates_, batch_tags_, dimension_}, values_);
  }

  /// Level 1: plain Monte Carlo, sample i from the stream (level 1, chain i, step 0), in batches of
  /// N_s (the batches change nothing: every sample is its own stream).
  void SampleMonteCarloLevel() {
    for (std::int64_t first = 0; first < n_; first += ns_) {
      const std::int64_t batch = std::min(ns_, n_ - first);
      candidates_.resize(static_cast<std::size_t>(batch) * d_);
      values_.resize(static_cast<std::size_t>(batch));
      batch_tags_.resize(static_cast<std::size_t>(batch));
      tbb::parallel_for(std::int64_t{0}, batch, [&](std::int64_t b) {
        Stream(options_.seed, 1, static_cast<std::uint64_t>(first + b), 0)
            .Normals(std::span<double>(candidates_).subspan(b * d_, d_));
        batch_tags_[b] = EvaluationTag{1, static_cast<int>(first + b), 0};
      });
      Evaluate();
      for (std::int64_t b = 0; b < batch; ++b) {
        g_[first + b] = values_[b];
        selection_.Offer(SampleKey{values_[b], first + b, batch_tags_[b], first + b}, &candidates_[b * d_]);
        failures_seen_.Offer(&candidates_[b * d_], d_, values_[b], batch_tags_[b]);
      }
    }
    layout_ = MakeLayout(n_, n_);  // level 1: N chains of one sample, so gamma = 0
    level_evaluations_ = n_;
    level_failed_ = std::count_if(g_.begin(), g_.end(), [](double v) { return std::isnan(v); });
    level_ancestors_ = n_;
  }

  /// The current level's record as its sampling left it (evaluations, failed ones, acceptance rate,
  /// scale lambda, ancestors), its evaluations counted into the result.
  SubsetLevel SampledRecord() {
    SubsetLevel record;
    record.evaluations = level_evaluations_;
    record.failed_evaluations = level_failed_;
    record.acceptance_rate = level_acceptance_;
    record.scale = level_scale_;
    record.ancestors = level_ancestors_;
    result_.evaluations += record.evaluations;
    result_.failed_evaluations += record.failed_evaluations;
    return record;
  }

  /// The level's threshold, P_j (the fraction of its N values at or below it), gamma_j and delta_j
  /// into `record`, which joins the result.
  void MeasureLevel(int level, double threshold, SubsetLevel& record) {
    std::vector<char> hit(static_cast<std::size_t>(n_));
    for (std::int64_t i = 0; i < n_; ++i) hit[i] = g_[i] <= threshold ? 1 : 0;
    const auto hits = std::count(hit.begin(), hit.end(), char{1});
    record.threshold = threshold;
    record.conditional_probability = static_cast<double>(hits) / static_cast<double>(n_);
    record.correlation_factor =
        level == 1 ? 0 : CorrelationFactor(hit, layout_, record.conditional_probability);
    record.coefficient_of_variation = LevelCov(record.conditional_probability, n_, record.correlation_factor);
    result_.levels.push_back(record);
    deltas_.push_back(record.coefficient_of_variation);
  }

  /// The last level: converged (N_s or more of its samples fail) or at the level cap (then the bound
  /// P < prod P_j * N_s / N); P = prod P_j; the failing samples met at this level.
  void Conclude(std::int64_t failures, double conditional_probability) {
    result_.status = failures >= ns_ ? SubsetResult::Status::kConverged : SubsetResult::Status::kLevelCap;
    result_.probability = product_ * conditional_probability;
    if (result_.status == SubsetResult::Status::kLevelCap) {
      result_.upper_bound = product_ * static_cast<double>(ns_) / static_cast<double>(n_);
    }
    result_.failure_count = failures_seen_.count;
    if (failures_seen_.count > 0) {
      result_.failure_mean = failures_seen_.sum;
      for (double& v : result_.failure_mean) v /= static_cast<double>(failures_seen_.count);
      result_.most_likely_failure = failures_seen_.nearest;
      result_.most_likely_failure_tag = failures_seen_.nearest_tag;
      result_.most_likely_failure_value = failures_seen_.nearest_g;
    }
  }

  /// Seeds: the N_s smallest values (slots of selection_), in an order shuffled by (seed, level + 1)
  /// so that the groups of the adaptation are not sorted by g (Papaioannou et al. 2015).
  std::vector<std::int64_t> ShuffledSeeds(int level) const {
    const std::vector<std::int64_t> sorted = selection_.Sorted();
    GESWEEP_DEMAND(static_cast<std::int64_t>(sorted.size()) == ns_);
    std::vector<std::int64_t> seeds(sorted);
    const Stream shuffle(options_.seed, level + 1, kSeedShuffleChain, 0);
    for (std::int64_t i = ns_ - 1; i > 0; --i) {
      const auto j = static_cast<std::int64_t>(
          shuffle.Uniform(kPurposeUniform, static_cast<std::uint64_t>(i)) * static_cast<double>(i + 1) -
          0x1.0p-60);
      std::swap(seeds[i], seeds[std::clamp<std::int64_t>(j, 0, i)]);
    }
    return seeds;
  }

  /// Chain c of `next` starts at seed c (its point, value, tag and ancestor), its sample at step 0
  /// offered to the next level's selection and failure record; the distinct ancestors counted.
  void StartChains(ChainLevel& next, const std::vector<std::int64_t>& seeds) {
    next_selection_.Clear();
    failures_seen_.Reset(d_);
    for (std::int64_t c = 0; c < ns_; ++c) {
      const std::int64_t at = next.layout.offset[c];
      std::copy(selection_.point(seeds[c]), selection_.point(seeds[c]) + d_, state_.begin() + c * d_);
      next.g[at] = selection_.key(seeds[c]).g;
      state_tag_[c] = selection_.key(seeds[c]).tag;
      state_ancestor_[c] = selection_.key(seeds[c]).ancestor;
      next_selection_.Offer(SampleKey{next.g[at], at, state_tag_[c], state_ancestor_[c]}, &state_[c * d_]);
      failures_seen_.Offer(&state_[c * d_], d_, next.g[at], state_tag_[c]);
    }
    std::vector<std::int64_t> distinct(state_ancestor_);
    std::sort(distinct.begin(), distinct.end());
    level_ancestors_ = std::unique(distinct.begin(), distinct.end()) - distinct.begin();
  }

  /// The chains of `next` in options_.adaptation_groups groups, lambda adapted after each group
  /// towards the target acceptance; the level's evaluations, acceptance rate and final scale.
  void RunChains(ChainLevel& next) {
    std::int64_t accepted_total = 0, proposed_total = 0;
    level_evaluations_ = 0;
    level_failed_ = 0;
    const int groups = options_.adaptation_groups;
    for (int group = 0; group < groups; ++group) {
      std::int64_t accepted = 0, proposed = 0;
      RunGroup(next, ns_ * group / groups, ns_ * (group + 1) / groups, accepted, proposed);
      if (proposed > 0) {
        const double rate = static_cast<double>(accepted) / static_cast<double>(proposed);
        lambda_ = std::exp(std::log(lambda_) + (rate - options_.target_acceptance) / std::sqrt(group + 1.0));
      }
      accepted_total += accepted;
      proposed_total += proposed;
    }
    level_acceptance_ =
        proposed_total > 0 ? static_cast<double>(accepted_total) / static_cast<double>(proposed_total) : 0;
    level_scale_ = lambda_;
  }

  /// The chains [first, end) of `next`, stepped together (one batch of candidates a step) until each
  /// has its length; their accepted and proposed moves counted.
  void RunGroup(ChainLevel& next, std::int64_t first, std::int64_t end, std::int64_t& accepted,
                std::int64_t& proposed) {
    // One scale for every component. Papaioannou et al. (2015) scale component k by the seeds'
    // standard deviation s_k; but s_k is a function of the seeds, so the kernel then depends on the
    // chains' own starting states: in 1000 dimensions that coupling pulled the chi-square level's
    // chains towards the threshold and biased each conditional probability by about -12 %
    // (docs/dispersion.md). A scalar lambda does not see the seeds.
    const double sigma = std::min(lambda_, 1.0), rho = std::sqrt(1 - sigma * sigma);
    for (std::int64_t step = 1;; ++step) {
      active_.clear();
      for (std::int64_t c = first; c < end; ++c) {
        if (step < next.layout.length[c]) active_.push_back(c);
      }
      if (active_.empty()) break;
      Propose(next.number, step, sigma, rho);
      Evaluate();
      level_evaluations_ += static_cast<std::int64_t>(active_.size());
      Accept(next, step, accepted, proposed);
    }
  }

  /// A candidate from each active chain's point, from its stream (level, chain, step): Crank-Nicolson
  /// rho * x + sigma * v, or the modified Metropolis component by component.
  void Propose(int level, std::int64_t step, double sigma, double rho) {
    const auto batch = active_.size();
    candidates_.resize(batch * d_);
    values_.resize(batch);
    batch_tags_.resize(batch);
    tbb::parallel_for(std::size_t{0}, batch, [&](std::size_t b) {
      const std::int64_t c = active_[b];
      const double* current = &state_[c * d_];
      std::span<double> v(candidates_.data() + b * d_, d_);
      const Stream stream(options_.seed, level, static_cast<std::uint64_t>(c), static_cast<int>(step));
      stream.Normals(v);
      if (options_.sampler == ConditionalSampler::kCrankNicolson) {
        for (std::size_t k = 0; k < d_; ++k) v[k] = rho * current[k] + sigma * v[k];
      } else {
        for (std::size_t k = 0; k < d_; ++k) {
          const double proposal = current[k] + sigma * v[k];
          const double ratio = std::exp(-0.5 * (proposal * proposal - current[k] * current[k]));
          v[k] = stream.Uniform(kPurposeUniform, k) <= ratio ? proposal : current[k];
        }
      }
      batch_tags_[b] = EvaluationTag{level, static_cast<int>(c), static_cast<int>(step)};
    });
  }

  /// Each active chain moves to its candidate when g there is at or below the threshold (NaN: it
  /// stays), and its sample at this step is offered to the next level's selection and failure record.
  void Accept(ChainLevel& next, std::int64_t step, std::int64_t& accepted, std::int64_t& proposed) {
    for (std::size_t b = 0; b < active_.size(); ++b) {
      const std::int64_t c = active_[b];
      const std::int64_t here = next.layout.offset[c] + step;
      const bool accept = values_[b] <= next.threshold;  // false for NaN
      if (accept) {
        std::copy(candidates_.begin() + b * d_, candidates_.begin() + (b + 1) * d_, state_.begin() + c * d_);
        next.g[here] = values_[b];
        state_tag_[c] = batch_tags_[b];
      } else {
        next.g[here] = next.g[here - 1];
      }
      next_selection_.Offer(SampleKey{next.g[here], here, state_tag_[c], state_ancestor_[c]},
                            &state_[c * d_]);
      failures_seen_.Offer(&state_[c * d_], d_, next.g[here], state_tag_[c]);
      // A NaN candidate is a failed evaluation of this level even though the chain stays put.
      if (std::isnan(values_[b])) ++level_failed_;
      accepted += accept ? 1 : 0;
      ++proposed;
    }
  }

  /// P's coefficient of variation from the levels' delta_j: sqrt(sum delta_j^2) (levels taken as
  /// uncorrelated), the fully correlated bound sum delta_j, and the lognormal 95 % interval.
  void CombineLevels() {
    double sum2 = 0, sum = 0;
    for (const double delta : deltas_) {
      sum2 += delta * delta;
      sum += delta;
    }
    result_.coefficient_of_variation = std::sqrt(sum2);
    result_.coefficient_of_variation_upper = sum;
    LognormalInterval95(result_.probability, result_.coefficient_of_variation, result_.interval_95_low,
                        result_.interval_95_high);
  }

  const LimitStateBatch& limit_state_;
  const int dimension_;
  const SubsetOptions& options_;
  const std::int64_t n_;   ///< N, samples per level
  const std::int64_t ns_;  ///< N_s = N * p0, the seeds (chains) of a conditional level
  const std::size_t d_;
  SubsetResult result_;
  std::vector<double> g_;  ///< the current level's values, by position
  SeedSelection selection_, next_selection_;
  FailureRecord failures_seen_;
  std::vector<double> candidates_, values_;  ///< one batch: its points (row-major) and g there
  std::vector<EvaluationTag> batch_tags_;
  std::vector<std::int64_t> active_;  ///< the chains of a step's batch
  ChainLayout layout_;                ///< the current level's chains
  double lambda_;
  double level_acceptance_ = 1, level_scale_ = 0;
  std::int64_t level_evaluations_ = 0, level_failed_ = 0, level_ancestors_ = 0;
  double product_ = 1;  ///< prod of the previous levels' P_j
  std::vector<double> deltas_;
  std::vector<double> state_;                 ///< the chains' current points
  std::vector<EvaluationTag> state_tag_;      ///< the evaluations that gave them
  std::vector<std::int64_t> state_ancestor_;  ///< their Monte Carlo ancestors
};

}  // namespace

SubsetResult RunSubsetSimulation(const LimitStateBatch& limit_state, int dimension,
                                 const SubsetOptions& options) {
  const std::string source = "subset simulation";
  ValidateSubsetOptions(options, source);
  if (dimension < 1) throw InputError(source, "dimension", std::to_string(dimension), "an integer >= 1");
  GESWEEP_DEMAND(static_cast<bool>(limit_state));
  return SubsetRun(limit_state, dimension, options).Run();
}

}  // namespace gesweep::rare
