#pragma once
/// Subset simulation (Au & Beck, Probabilistic Engineering Mechanics 16, 2001) in a standard-normal
/// space of any dimension (docs/dispersion.md, "Subset simulation: the method and its analytic check").
///
/// The event is F = {u : g(u) <= 0}, u ~ N(0, I_d). P(F) is written as a product of conditional
/// probabilities of nested events F_j = {g(u) <= b_j}, b_1 > b_2 > ... > b_m = 0, each about p0:
///   level 1:  N plain Monte Carlo samples; b_1 is their p0-quantile of g (the midpoint of the
///             N_s-th and (N_s+1)-th smallest values, N_s = N p0);
///   level j:  the N_s samples of level j-1 with g <= b_{j-1} seed N_s Markov chains that sample the
///             standard normal conditioned on F_{j-1}; together N samples (the seeds included);
///   stop at the first level where at least N_s samples have g <= 0:
///             P = p0^(m-1) * P_m,  P_m = (number with g <= 0) / N.
/// A level cap bounds the work: when the cap is reached and fewer than N_s samples fail, the
/// result says that P is below p0^cap (with the estimate of the last level when it has failures).
///
/// The conditional sampler is the preconditioned Crank-Nicolson proposal (default; Cotter et al.
/// 2013, Papaioannou et al. 2015 "conditional sampling") v = rho u + sigma xi with
/// rho = sqrt(1 - sigma^2), which leaves N(0, I) invariant, so the candidate is accepted exactly
/// when g(v) <= b: its acceptance does not decay with the dimension. The component-wise modified
/// Metropolis of Au & Beck (proposal N(u_k, sigma^2) per component, each accepted with
/// min(1, phi(v_k) / phi(u_k))) is the alternative (kModifiedMetropolis).
/// Both scale their proposal adaptively per level (after Papaioannou et al. 2015, algorithm 5): the
/// chains of a level run in groups; after each group, lambda <- lambda exp((a - a*) / sqrt(i)) with a
/// the group's acceptance rate, a* = 0.44 and i the group's number; sigma = min(lambda, 1) for
/// every component (not lambda times the seeds' per-component spread, as in the paper: that couples
/// the kernel to the chains' starting states and biased the high-dimensional chi-square test).
///
/// Reproducible: every random number is a pure function of (seed, level, chain, step, component)
/// through the counter-based SplitMix64 hash of engine/disturbance/run_noise.h. The chains of a
/// group advance in lock step and each step's candidates are handed to the limit state as one batch,
/// so the result does not depend on threads or on the order in which a batch is evaluated.

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "engine/common/enum_names.h"

namespace gesweep::rare {

/// Conditional sampler of the levels after the first.
enum class ConditionalSampler : int {
  kCrankNicolson = 0,       ///< preconditioned Crank-Nicolson (default)
  kModifiedMetropolis = 1,  ///< component-wise modified Metropolis (Au & Beck 2001)
};

/// Settings of one subset simulation.
struct SubsetOptions {
  double level_probability = 0.1;  ///< p0, in (0, 1); N * p0 must be an integer >= 1
  int samples_per_level = 1000;    ///< N
  int max_levels = 20;             ///< the level cap m_max (level 1 is the Monte Carlo level)
  std::uint64_t seed = 0;          ///< every random number is a function of (seed, level, chain, step)
  ConditionalSampler sampler = ConditionalSampler::kCrankNicolson;
  double initial_scale = 0.6;       ///< lambda at level 2, in (0, 1] (Papaioannou et al. 2015)
  double target_acceptance = 0.44;  ///< a*, in (0, 1)
  int adaptation_groups = 10;       ///< groups of chains per level, lambda updated after each; 1..N_s
  /// The fewest chains N * p0 a level may have (1: the method's minimum). A caller that reports the
  /// chains' correlation asks for more (the landing risk asks for 10, docs/dispersion.md).
  int min_chains = 1;
};

/// Refuses options that cannot run, as an InputError naming `source`, the key, the value and the
/// expectation (p0 outside (0, 1), N * p0 not an integer >= 1, a level cap below 1, ...).
void ValidateSubsetOptions(const SubsetOptions& options, const std::string& source);

/// Where an evaluation belongs: level (1-based), chain (0-based; the sample's index at level 1), and
/// step within the chain (0 at level 1; 1.. for the chains' candidates). A limit state that runs a
/// simulation can record it so that the evaluation can be found again.
struct EvaluationTag {
  int level = 0;
  int chain = 0;
  int step = 0;
};

/// A batch of points of R^d, row-major: point i is points[i*d .. i*d + d).
struct PointBatch {
  std::span<const double> points;
  std::span<const EvaluationTag> tags;
  int dimension = 0;
  std::size_t size() const { return tags.size(); }
  std::span<const double> point(std::size_t i) const {
    return points.subspan(i * static_cast<std::size_t>(dimension), static_cast<std::size_t>(dimension));
  }
};

/// The limit state over a batch: values[i] = g(point i); failure is g <= 0. A NaN value is a failed
/// evaluation: it is counted and reported, and the point is taken as outside every intermediate
/// event (as g = +infinity). The callback may evaluate the batch in any order and on any threads.
using LimitStateBatch = std::function<void(const PointBatch& batch, std::span<double> values)>;

/// A batch limit state from a pointwise one, evaluated with tbb::parallel_for over the batch (the
/// calling thread's task arena decides the threads). `g` must be safe to call concurrently.
LimitStateBatch ParallelLimitState(std::function<double(std::span<const double> u)> g);

/// One level of a run.
struct SubsetLevel {
  double threshold = 0;                 ///< b_j (0 at the last level)
  double conditional_probability = 0;   ///< P_j = fraction of the level's N samples with g <= b_j
  double coefficient_of_variation = 0;  ///< delta_j = sqrt((1 - P_j) / (N P_j) (1 + gamma_j))
  double correlation_factor = 0;        ///< gamma_j (0 at the Monte Carlo level)
  double acceptance_rate = 0;           ///< accepted / proposed over the level's chains (1 at level 1)
  double scale = 0;                     ///< lambda after the level's last group (0 at level 1)
  std::int64_t evaluations = 0;         ///< limit-state evaluations of the level
  std::int64_t failed_evaluations = 0;  ///< of those, NaN values
  /// How many of the Monte Carlo level's samples the level's N samples descend from (N at level 1,
  /// at most N_s after): a count far below N_s says the chains have collapsed onto few families, and
  /// that delta_j, which sees only the correlation within chains, understates the error.
  std::int64_t ancestors = 0;
};

/// What a run gives.
struct SubsetResult {
  /// kConverged: the last level has at least N_s failures; kLevelCap: the cap was reached first;
  /// kTooManyFailedEvaluations: a level had fewer than N_s non-NaN values, so no threshold could be
  /// set (probability NaN; failed_evaluations says how many).
  enum class Status : int { kConverged = 0, kLevelCap = 1, kTooManyFailedEvaluations = 2 };
  Status status = Status::kConverged;
  double probability = 0;               ///< p0^(m-1) P_m (under kLevelCap: from the last level, maybe 0)
  double coefficient_of_variation = 0;  ///< sqrt(sum_j delta_j^2): levels taken as uncorrelated
  double coefficient_of_variation_upper = 0;  ///< sum_j delta_j: the fully correlated bound
  double interval_95_low = 0;                 ///< lognormal interval from coefficient_of_variation
  double interval_95_high = 0;
  double upper_bound = 0;               ///< under kLevelCap: P < p0^cap; else 0
  std::int64_t evaluations = 0;         ///< N + (m - 1)(N - N_s)
  std::int64_t failed_evaluations = 0;  ///< NaN values over all levels
  int dimension = 0;
  std::vector<SubsetLevel> levels;
  /// The samples of the last level with g <= 0 (a chain's repeated state counted each time, as in the
  /// estimate): how many, their mean point (the "design point" of the event as a mean; empty when
  /// none) and the one nearest the origin, the most likely under N(0, I), with the tag of the
  /// evaluation that gave it (a seed's or a repeated state's own evaluation) and its value g.
  std::int64_t failure_count = 0;
  std::vector<double> failure_mean;
  std::vector<double> most_likely_failure;
  EvaluationTag most_likely_failure_tag;
  double most_likely_failure_value = 0;
  std::string Summary() const;  ///< one line: P, CoV, interval, levels, evaluations
};

/// Runs subset simulation of `limit_state` in `dimension` standard-normal dimensions. Memory: about
/// 4 N_s * dimension doubles and N values, whatever N (a level's points are not kept: only the two
/// levels' seeds, the chains' states and one batch of at most N_s candidates). Throws
/// InputError (through ValidateSubsetOptions, with source "subset simulation") for options that
/// cannot run or a dimension below 1.
SubsetResult RunSubsetSimulation(const LimitStateBatch& limit_state, int dimension,
                                 const SubsetOptions& options);

/// The lognormal 95 % interval of an estimate p with coefficient of variation cov: ln P normal with
/// variance s^2 = ln(1 + cov^2) and mean ln p - s^2 / 2 (so that the mean of P is p);
/// the interval is exp(mean -/+ 1.959964 s).
void LognormalInterval95(double p, double cov, double& low, double& high);

}  // namespace gesweep::rare

namespace gesweep {
/// The samplers' names in a study's [subset] table and in the archive.
GESWEEP_ENUM_NAMES(rare::ConditionalSampler, {kCrankNicolson, "crank_nicolson"},
                   {kModifiedMetropolis, "modified_metropolis"});
}  // namespace gesweep
