#pragma once
/// The landing risk by subset simulation (docs/dispersion.md, "Landing risk by subset simulation"):
/// a study with a [subset] table names limits on the landing's results ("touchdown_sink_rate_mps >
/// 3.05"), and for every cell of its design (every row: e.g. with and without the h-derivatives) and
/// every limit, RunRisk estimates the probability that a landing in the study's turbulence exceeds
/// it, with engine/rare's subset simulation in the standard-normal space of the landing's noise
/// (RunNoise's point layout, engine/disturbance/run_noise.h).
///
/// Every landing of every level is one Evaluation, kept in the archive with its (cell, limit,
/// level, chain, step): the recipe that makes it again. Its noise is a pure function of the study's
/// seed, its tag and the values of the evaluations before it, so RunRisk over the stored values
/// (RiskRunOptions::cache) flies nothing, reaches the same points bit for bit, and can fly any one
/// of them again (a replay) or the ones that are missing (a resume).

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "engine/archive/subset_archive.h"
#include "engine/rare/repetitions.h"
#include "engine/rare/subset_simulation.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep::risk {

/// A limit event on one scalar result column of the landing.
struct RiskLimit {
  std::string text;    ///< as written, e.g. "touchdown_sink_rate_mps > 3.05"
  std::string column;  ///< the column's name, e.g. "touchdown_sink_rate_mps"
  std::string path;    ///< its archive path, e.g. "results/landing/touchdown_sink_rate_mps"
  std::string units;
  int column_index = 0;  ///< in the plan's schema
  bool above = true;     ///< ">" (the event is value > limit) or "<"
  double value = 0;
};

/// What the study's [subset] table says.
struct RiskSpec {
  rare::SubsetOptions subset;  ///< p0, N, the level cap, the seed, the sampler
  std::vector<RiskLimit> limits;
  /// K: independent subset simulations per (cell, limit), each with its own seed, pooled
  /// (engine/rare/repetitions.h): the spread of the K estimates is their measured error.
  int repetitions = 1;
  /// A hash of everything that decides the evaluations (the study's fingerprint, the options and
  /// the limits): a resume refuses a journal of another spec.
  std::uint64_t fingerprint = 0;
};

/// Reads and checks the [subset] table of the plan's study; throws InputError naming the study file,
/// the key (subset.level_probability, ...), the value, the expectation and the line. Refuses a study
/// without a landing analysis, without turbulence, or with time series stored.
RiskSpec ReadRiskSpec(const SweepPlan& plan);

/// The columns an evaluation keeps: every float64 scalar column of the plan's schema, schema order.
std::vector<int> RiskColumns(const SweepPlan& plan);

/// The cells of the plan's design, each with its own estimates: its rows (single, grid, list), or one
/// for a monte_carlo design, whose parameters are random inputs of every landing instead.
std::int64_t CellCount(const SweepPlan& plan);

/// The random parameters of the landings (docs/dispersion.md, "Random parameters"): a monte_carlo
/// design's parameters, in its column order, each one coordinate of the standard-normal space after
/// the noise's, mapped to its value through its inverse CDF (MonteCarloValueAtNormal); empty for
/// every other design.
std::span<const DesignParameter> CellRandomParameters(const SweepPlan& plan);

/// The random parameters' values at their coordinates (`coordinates`: one per random parameter).
std::vector<double> RandomParameterValues(const SweepPlan& plan, std::span<const double> coordinates);

/// The parameters of one cell (a design row over the study's fixed parameters; a monte_carlo
/// design's one cell: its parameters at their medians).
RunParameters CellParameters(const SweepPlan& plan, std::int64_t cell);

/// The noise's part of a cell's dimension (the landing's LandingNoiseDimension).
std::uint64_t CellNoiseDimension(const SweepPlan& plan, std::int64_t cell);

/// The standard-normal dimension of a cell's landings: the noise's coordinates (RunNoise's point
/// layout), then one per random parameter.
std::uint64_t CellDimension(const SweepPlan& plan, std::int64_t cell);

/// Flies the landing of `cell` at `point` (CellDimension coordinates) into row 0 of `block`:
/// ExecuteRun with the point's noise part and the random parameters' values at its last coordinates.
/// What every evaluation, replay and design-point series flies.
void ExecuteCellRun(const SweepPlan& plan, std::int64_t cell, RunWorkspace& workspace, ResultBlock& block,
                    std::span<const double> point, const std::atomic<bool>* cancel = nullptr);

/// The interval, s, at which a cell's noise streams are held (the sample interval of its turbulence).
double CellSampleInterval(const SweepPlan& plan, std::int64_t cell);

/// "h_derivatives = 0, wind_20ft_mps = -15.43" (empty for a design of one run).
std::string CellLabel(const SweepPlan& plan, std::int64_t cell);

/// The seed of one (cell, limit, repetition) subset simulation: SplitMix64 of the study's seed and
/// the pair, and of the repetition for repetitions after the first (so that repetition 0 is the
/// simulation of a study without repetitions).
std::uint64_t SimulationSeed(std::uint64_t seed, std::int64_t cell, std::int64_t limit,
                             std::int64_t repetition = 0);

/// Flies the landing of `cell` with noise `point` and evaluates limit `limit` on it (g is NaN when
/// `limit` is negative). Never throws for a failed run.
Evaluation FlyPoint(const SweepPlan& plan, std::int64_t cell, int limit, const RiskSpec& spec,
                    std::span<const double> point, const std::atomic<bool>* cancel = nullptr);

/// One (cell, limit) estimate.
struct LimitRisk {
  std::int64_t cell = 0;
  int limit = 0;
  /// The first repetition's run: its levels, thresholds, exceedance curve and design point are the
  /// ones reported and drawn.
  rare::SubsetResult subset;
  /// Repetitions 1 .. K-1 (empty for K = 1).
  std::vector<rare::SubsetResult> other_repetitions;
  /// All K pooled: the estimate reported (for K = 1, the first run's own).
  rare::PooledEstimate pooled;
  std::uint64_t dimension = 0;
  /// The failing landings of the first repetition's last level: the row (in RiskRun::evaluations) of
  /// the most likely one (the failing point nearest the origin), -1 when none failed.
  std::int64_t most_likely_row = -1;
};

/// The processes a run's landings are spread over (`gesweep risk --mpi`: the MPI ranks of
/// engine/mpi/risk_exchange.h; nothing here knows how the bytes travel). Every process runs the same
/// driver with the same seeds, so every process proposes the same batches of points; each flies its
/// share of a batch's landings that are not in the cache (dealt round the processes in turn,
/// batch after batch), and AllGather gives every process every share, so that the driver goes on alike
/// everywhere. No point is ever sent: only the landings' Evaluations, with each process's stop flag
/// and a hash of the batch it proposed (so that every process knows it flew the same points).
class BatchExchange {
 public:
  virtual ~BatchExchange() = default;
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  /// Collective: every process passes its bytes; each receives every process's, by rank.
  virtual std::vector<std::vector<unsigned char>> AllGather(std::span<const unsigned char> mine) = 0;
};

/// What RunRisk gives.
struct RiskRun {
  std::vector<LimitRisk> results;       ///< cell-major: cell 0's limits, then cell 1's, ...
  std::vector<Evaluation> evaluations;  ///< every landing, in the order they were made
  bool cancelled = false;               ///< stopped by the flag: `results` is incomplete
  std::int64_t flown_here = 0;          ///< landings this process flew (not taken from the cache)
  /// With an exchange: a process proposed other points than process 0 (different floating-point
  /// results on different machines); the run stopped there, as `cancelled`, and this says where.
  std::string diverged;
};

struct RiskRunOptions {
  const std::atomic<bool>* cancel = nullptr;
  /// Evaluations already made (a resume, a replay): taken instead of flying them.
  const std::map<EvaluationKey, Evaluation>* cache = nullptr;
  /// Called after each batch with its new evaluations (not those from the cache), in order: the journal.
  std::function<void(std::span<const Evaluation>)> on_batch;
  /// One line per level (may be empty).
  std::function<void(const std::string&)> progress;
  /// A replay: the point of this evaluation is copied into *captured_point when it is reached.
  /// The run stops once it has been captured.
  std::optional<EvaluationKey> capture;
  std::vector<double>* captured_point = nullptr;
  /// Only this (cell, limit, repetition) simulation (a replay); all when empty.
  std::optional<std::tuple<std::int64_t, int, int>> only;
  /// The processes each batch is spread over (every one calls RunRisk alike, with the same cache);
  /// null: this process flies every landing. With one, `cancel` is read when a batch is exchanged,
  /// and a batch stops on every process when any was asked to stop; `on_batch` and `progress` are
  /// given only on the process that journals and prints (its rank 0).
  BatchExchange* exchange = nullptr;
  /// The landings of a batch flown `lanes` at a time in SIMD lanes (ExecuteRuns, one of kLaneWidths;
  /// 1: one at a time, ExecuteCellRun). Every evaluation is the same bit for bit whatever it is.
  int lanes = DefaultLanes();
};

/// Runs every (cell, limit) subset simulation of the plan's design. The threads are the calling
/// thread's task arena's; the result does not depend on them.
RiskRun RunRisk(const SweepPlan& plan, const RiskSpec& spec, const RiskRunOptions& options);

/// The exceedance curve of one estimate: P(X > x) (or P(X < x)) at the intermediate thresholds
/// x_j (where it is the product of the first j levels' conditional probabilities) and at the limit,
/// with the lognormal 95 % band of the levels' accumulated coefficient of variation.
struct ExceedancePoint {
  double value = 0;  ///< x, in the column's units
  double probability = 0;
  double coefficient_of_variation = 0;
  double low = 0, high = 0;
};
std::vector<ExceedancePoint> ExceedanceCurve(const LimitRisk& risk, const RiskLimit& limit);

}  // namespace gesweep::risk
