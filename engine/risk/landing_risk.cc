#include "engine/risk/landing_risk.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>

#include "engine/common/errors.h"
#include "engine/common/toml_reader.h"
#include "engine/disturbance/run_noise.h"
#include "engine/risk/risk_archive.h"
#include "engine/sweep/runner.h"

namespace gesweep::risk {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::int64_t kMaxCells = 64;
constexpr std::size_t kMaxLimits = 16;
constexpr long long kMaxSeed = 9007199254740992LL;  // 2^53, as a sweep's seeds
/// The fewest chains a study's level may have (N * p0): below it the chains' correlation, and so the
/// coefficient of variation, rests on too few chains to report.
constexpr int kMinChains = 10;
constexpr long long kMaxRepetitions = 1000;

/// Thrown by the limit state once the cancellation flag is seen after a batch; RunRisk catches it.
struct Cancelled {};
/// Thrown once a replay's evaluation has been reached.
struct Captured {};

std::string Trim(std::string_view text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string_view::npos) return "";
  const auto last = text.find_last_not_of(" \t");
  return std::string(text.substr(first, last - first + 1));
}

std::uint64_t Mix(std::uint64_t hash, std::uint64_t value) {
  return SplitMix64Mix(hash ^ SplitMix64Mix(value + 1));
}

std::uint64_t MixText(std::uint64_t hash, const std::string& text) {
  hash = Mix(hash, text.size());
  for (const unsigned char c : text) hash = Mix(hash, c);
  return hash;
}

/// The scalar float64 result columns a limit may name, by their name (the path's last part).
std::string LimitColumnNames(const SweepPlan& plan) {
  std::string names;
  for (const auto& column : plan.schema().columns) {
    if (column.width != 1 || column.type != ColumnType::kFloat64 || column.path.rfind("results/", 0) != 0)
      continue;
    if (!names.empty()) names += ", ";
    names += column.path.substr(column.path.rfind('/') + 1);
  }
  return names;
}

RiskLimit ParseRiskLimit(const SweepPlan& plan, const std::string& text, const TomlSection& section) {
  const auto fail = [&](const std::string& why) { section.Fail("limits", "\"" + text + "\"", why); };
  const auto at = text.find_first_of("<>");
  if (at == std::string::npos || text.find_first_of("<>", at + 1) != std::string::npos) {
    fail("a limit 'COLUMN > VALUE' or 'COLUMN < VALUE', e.g. \"touchdown_sink_rate_mps > 3.05\"");
  }
  RiskLimit limit;
  limit.text = text;
  limit.above = text[at] == '>';
  limit.column = Trim(std::string_view(text).substr(0, at));
  const std::string number = Trim(std::string_view(text).substr(at + 1));
  char* end = nullptr;
  errno = 0;
  limit.value = number.empty() ? kNaN : std::strtod(number.c_str(), &end);
  if (number.empty() || end != number.c_str() + number.size() || errno == ERANGE ||
      !std::isfinite(limit.value)) {
    fail("a finite number after '" + std::string(1, text[at]) + "'");
  }
  const auto& columns = plan.schema().columns;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    const auto& column = columns[c];
    if (column.width != 1 || column.type != ColumnType::kFloat64 || column.path.rfind("results/", 0) != 0)
      continue;
    if (column.path.substr(column.path.rfind('/') + 1) != limit.column) continue;
    limit.path = column.path;
    limit.units = column.units;
    limit.column_index = static_cast<int>(c);
    return limit;
  }
  section.Fail("limits", "\"" + text + "\"",
               "a limit on a scalar result column of the study's analyses: one of " + LimitColumnNames(plan));
}

rare::SubsetOptions ReadSubsetOptions(const TomlSection& section) {
  rare::SubsetOptions options;
  if (const auto p0 = section.OptionalNumber("level_probability")) options.level_probability = *p0;
  const auto integer = [&](std::string_view key, long long low, long long high, auto& target) {
    const auto value = section.OptionalInteger(key);
    if (!value) return;
    if (*value < low || *value > high) {
      section.Fail(key, std::to_string(*value),
                   "an integer from " + std::to_string(low) + " to " + std::to_string(high));
    }
    target = static_cast<std::remove_reference_t<decltype(target)>>(*value);
  };
  integer("samples_per_level", 1, 10'000'000, options.samples_per_level);
  integer("max_levels", 1, 100, options.max_levels);
  integer("seed", 0, kMaxSeed, options.seed);
  integer("adaptation_groups", 1, 10'000'000, options.adaptation_groups);
  if (const auto sampler = section.OptionalString("sampler")) {
    if (const auto named = ParseEnum<rare::ConditionalSampler>(*sampler)) {
      options.sampler = *named;
    } else {
      section.Fail("sampler", "\"" + *sampler + "\"",
                   EnumChoices<rare::ConditionalSampler>() + " (default: crank_nicolson)");
    }
  }
  if (const auto scale = section.OptionalNumber("initial_scale")) options.initial_scale = *scale;
  if (const auto target = section.OptionalNumber("target_acceptance")) options.target_acceptance = *target;
  // A study asks for more than the method's minimum of one chain: the coefficient of variation of a
  // level is estimated from the chains' correlation, which takes several chains (docs/dispersion.md).
  options.min_chains = kMinChains;
  try {
    rare::ValidateSubsetOptions(options, section.source());
  } catch (const InputError& e) {
    section.Fail(e.key(), e.value(), e.expected());
  }
  return options;
}

}  // namespace

std::vector<int> RiskColumns(const SweepPlan& plan) {
  std::vector<int> columns;
  const auto& all = plan.schema().columns;
  for (std::size_t c = 0; c < all.size(); ++c) {
    if (all[c].width == 1 && all[c].type != ColumnType::kComplex) columns.push_back(static_cast<int>(c));
  }
  return columns;
}

std::int64_t CellCount(const SweepPlan& plan) {
  return plan.design().spec().kind == DesignKind::kMonteCarlo ? 1 : plan.design_runs();
}

std::span<const DesignParameter> CellRandomParameters(const SweepPlan& plan) {
  if (plan.design().spec().kind != DesignKind::kMonteCarlo) return {};
  return plan.design().spec().parameters;
}

std::vector<double> RandomParameterValues(const SweepPlan& plan, std::span<const double> coordinates) {
  const auto random = CellRandomParameters(plan);
  GESWEEP_DEMAND(coordinates.size() == random.size());
  std::vector<double> values(random.size());
  for (std::size_t k = 0; k < random.size(); ++k)
    values[k] = MonteCarloValueAtNormal(random[k], coordinates[k]);
  return values;
}

namespace {

// The base parameters with the design's columns at `values` (design column order).
RunParameters WithDesignValues(const SweepPlan& plan, std::span<const double> values) {
  RunParameters parameters = plan.base_parameters();
  for (int c = 0; c < plan.design().column_count(); ++c) {
    parameters[static_cast<std::size_t>(plan.design().spec().parameters[static_cast<std::size_t>(c)].id)] =
        values[static_cast<std::size_t>(c)];
  }
  return parameters;
}

// The noise dimension a landing of `parameters` needs: the largest of the analyses'.
std::uint64_t NoiseDimensionOf(const SweepPlan& plan, const RunParameters& parameters) {
  std::uint64_t dimension = 0;
  for (const auto& analysis : plan.study().analyses) {
    dimension = std::max(dimension, analysis->NoiseDimension(parameters, *plan.study().aircraft));
  }
  return dimension;
}

}  // namespace

RunParameters CellParameters(const SweepPlan& plan, std::int64_t cell) {
  const auto random = CellRandomParameters(plan);
  if (!random.empty()) {
    // A random design's one cell: its parameters at their medians (the origin of their coordinates).
    const std::vector<double> origin(random.size(), 0.0);
    return WithDesignValues(plan, RandomParameterValues(plan, origin));
  }
  std::vector<double> row(static_cast<std::size_t>(plan.design().column_count()));
  plan.design().Row(cell, row.data());
  return WithDesignValues(plan, row);
}

std::uint64_t CellNoiseDimension(const SweepPlan& plan, std::int64_t cell) {
  return NoiseDimensionOf(plan, CellParameters(plan, cell));
}

std::uint64_t CellDimension(const SweepPlan& plan, std::int64_t cell) {
  return CellNoiseDimension(plan, cell) + CellRandomParameters(plan).size();
}

void ExecuteCellRun(const SweepPlan& plan, std::int64_t cell, RunWorkspace& workspace, ResultBlock& block,
                    std::span<const double> point, const std::atomic<bool>* cancel) {
  const auto random = CellRandomParameters(plan);
  if (random.empty()) {
    ExecuteRun(plan, cell, workspace, block, 0, cancel, point);
    return;
  }
  GESWEEP_DEMAND(point.size() >= random.size());
  const std::size_t noise = point.size() - random.size();
  const std::vector<double> values = RandomParameterValues(plan, point.subspan(noise));
  ExecuteRun(plan, cell, workspace, block, 0, cancel, point.first(noise), values);
}

double CellSampleInterval(const SweepPlan& plan, std::int64_t cell) {
  const RunParameters parameters = CellParameters(plan, cell);
  double interval = 0;
  for (const auto& analysis : plan.study().analyses) {
    interval = std::max(interval, analysis->NoiseSampleInterval(parameters));
  }
  return interval;
}

std::string CellLabel(const SweepPlan& plan, std::int64_t cell) {
  const auto random = CellRandomParameters(plan);
  if (!random.empty()) {
    std::string label;
    for (const DesignParameter& p : random) {
      if (!label.empty()) label += ", ";
      label += ParameterCatalog()[static_cast<std::size_t>(p.id)].name + " ~ " + DescribeDistribution(p);
    }
    return label;
  }
  std::vector<double> row(static_cast<std::size_t>(plan.design().column_count()));
  plan.design().Row(cell, row.data());
  std::string label;
  for (int c = 0; c < plan.design().column_count(); ++c) {
    const auto id = plan.design().spec().parameters[static_cast<std::size_t>(c)].id;
    const auto& info = ParameterCatalog()[static_cast<std::size_t>(id)];
    if (!label.empty()) label += ", ";
    const double value = row[static_cast<std::size_t>(c)];
    const auto level = static_cast<std::size_t>(value);
    label += info.name + " = " +
             (!info.levels.empty() && value >= 0 && level < info.levels.size() &&
                      static_cast<double>(level) == value
                  ? info.levels[level]
                  : ShortNumber(value));
  }
  return label;
}

std::uint64_t SimulationSeed(std::uint64_t seed, std::int64_t cell, std::int64_t limit,
                             std::int64_t repetition) {
  const std::uint64_t first =
      Mix(Mix(SplitMix64Mix(seed ^ 0x6c616e64696e6721ULL), static_cast<std::uint64_t>(cell)),
          static_cast<std::uint64_t>(limit));
  return repetition == 0 ? first : Mix(first ^ 0x7265706561746564ULL, static_cast<std::uint64_t>(repetition));
}

namespace {

// A random parameter may not lengthen the noise a landing needs (a longer time limit: a random start
// height, say): every point of the space has the dimension of the parameters' medians. Checked at
// each parameter's extreme values (the others at their medians); an extreme the landing refuses is
// a failed landing there, not a longer one.
void CheckRandomParametersKeepTheNoise(const SweepPlan& plan) {
  const auto random = CellRandomParameters(plan);
  if (random.empty()) return;
  const std::vector<double> origin(random.size(), 0.0);
  const std::vector<double> medians = RandomParameterValues(plan, origin);
  const std::uint64_t median_dimension = NoiseDimensionOf(plan, WithDesignValues(plan, medians));
  for (std::size_t k = 0; k < random.size(); ++k) {
    for (const double extreme : {random[k].lower, random[k].upper}) {
      std::vector<double> values = medians;
      values[k] = extreme;
      std::uint64_t needed = 0;
      try {
        needed = NoiseDimensionOf(plan, WithDesignValues(plan, values));
      } catch (const InputError&) {
        continue;
      }
      if (needed > median_dimension) {
        const std::string& name = ParameterCatalog()[static_cast<std::size_t>(random[k].id)].name;
        throw InputError(plan.study().path, "parameters." + name, ShortNumber(extreme),
                         "a random parameter that does not lengthen the landing's noise (at " +
                             ShortNumber(extreme) + " it needs " + std::to_string(needed) +
                             " coordinates, at its median " + std::to_string(median_dimension) +
                             "): make it a grid or list parameter, one cell per value",
                         plan.study().design_line);
      }
    }
  }
}

// What a [subset] study's design must be: a landing among its analyses, single, grid, list or
// monte_carlo, at most kMaxCells cells, each with a random input, no random parameter that lengthens
// the noise.
void CheckRiskDesign(const SweepPlan& plan) {
  const Study& study = plan.study();
  const bool has_landing = std::any_of(study.analyses.begin(), study.analyses.end(),
                                       [](const auto& a) { return a->name() == "landing"; });
  if (!has_landing) {
    throw InputError(study.path, "analyses", "",
                     "[analyses.landing]: a subset simulation estimates a landing's risk", study.subset_line);
  }
  const DesignKind kind = study.design.kind;
  if (kind != DesignKind::kSingle && kind != DesignKind::kGrid && kind != DesignKind::kList &&
      kind != DesignKind::kMonteCarlo) {
    throw InputError(study.path, "design.kind", std::string(ToString(kind)),
                     "single, grid or list (each design row a cell with its own estimates), or monte_carlo "
                     "(its parameters random inputs of every landing) with a [subset] table",
                     study.design_line);
  }
  if (CellCount(plan) > kMaxCells) {
    throw InputError(study.path, "design", std::to_string(plan.design_runs()) + " rows",
                     "at most " + std::to_string(kMaxCells) + " cells with a [subset] table (each runs " +
                         "a subset simulation per limit)",
                     study.design_line);
  }
  for (std::int64_t cell = 0; cell < CellCount(plan); ++cell) {
    if (CellDimension(plan, cell) == 0) {
      throw InputError(
          study.path, "parameters.turbulence", CellLabel(plan, cell),
          "turbulence = \"dryden\" in every cell, or random parameters (design.kind = \"monte_carlo\"): "
          "without either a landing has no random input for a subset simulation to sample",
          study.subset_line);
    }
  }
  CheckRandomParametersKeepTheNoise(plan);
}

// The [subset] table's limits, each parsed against the plan's result columns.
std::vector<RiskLimit> ReadRiskLimits(const SweepPlan& plan, const toml::table& table,
                                      const TomlSection& section) {
  std::vector<RiskLimit> parsed;
  const toml::node* limits = table.get("limits");
  const toml::array* array = limits != nullptr ? limits->as_array() : nullptr;
  if (array == nullptr || array->empty() || array->size() > kMaxLimits) {
    section.Fail("limits", limits == nullptr ? "" : DescribeNode(*limits),
                 "an array of 1 to " + std::to_string(kMaxLimits) +
                     " limits, e.g. limits = [\"touchdown_sink_rate_mps > 3.05\"]");
  }
  for (const auto& node : *array) {
    const auto text = node.value<std::string>();
    if (!text) section.Fail("limits", DescribeNode(node), "a string 'COLUMN > VALUE' or 'COLUMN < VALUE'");
    parsed.push_back(ParseRiskLimit(plan, *text, section));
  }

  return parsed;
}

// A hash of everything that decides the evaluations: the study, the options, the limits, and the
// repetitions when there are several.
std::uint64_t RiskFingerprint(const Study& study, const RiskSpec& spec) {
  std::uint64_t hash = Mix(0x7269736b2d303031ULL, study.fingerprint);
  const auto& o = spec.subset;
  for (const std::uint64_t v :
       {std::bit_cast<std::uint64_t>(o.level_probability), static_cast<std::uint64_t>(o.samples_per_level),
        static_cast<std::uint64_t>(o.max_levels), o.seed, static_cast<std::uint64_t>(o.sampler),
        std::bit_cast<std::uint64_t>(o.initial_scale), std::bit_cast<std::uint64_t>(o.target_acceptance),
        static_cast<std::uint64_t>(o.adaptation_groups)}) {
    hash = Mix(hash, v);
  }
  for (const auto& limit : spec.limits) hash = MixText(hash, limit.text);
  // Only when asked for: a study without repetitions keeps the fingerprint it had before they existed.
  if (spec.repetitions != 1)
    hash = Mix(hash ^ 0x7265706561747321ULL, static_cast<std::uint64_t>(spec.repetitions));
  return hash;
}
}  // namespace

RiskSpec ReadRiskSpec(const SweepPlan& plan) {
  const Study& study = plan.study();
  if (study.subset_line == 0) {
    throw InputError(study.path, "subset", "",
                     "a [subset] table (the limits and the method, docs/dispersion.md)");
  }
  const toml::table root = ParseToml(study.text, study.path);
  const toml::table* table = root["subset"].as_table();
  if (table == nullptr) throw InputError(study.path, "subset", "", "a table [subset]", study.subset_line);
  const TomlSection section(*table, study.path, "subset");
  section.RejectUnknownKeys({"limits", "level_probability", "samples_per_level", "max_levels", "seed",
                             "sampler", "initial_scale", "target_acceptance", "adaptation_groups",
                             "repetitions"});
  RiskSpec spec;
  spec.subset = ReadSubsetOptions(section);
  if (const auto repetitions = section.OptionalInteger("repetitions")) {
    if (*repetitions < 1 || *repetitions > kMaxRepetitions) {
      section.Fail("repetitions", std::to_string(*repetitions),
                   "an integer from 1 to " + std::to_string(kMaxRepetitions) +
                       " (independent subset simulations per cell and limit)");
    }
    spec.repetitions = static_cast<int>(*repetitions);
  }

  CheckRiskDesign(plan);
  spec.limits = ReadRiskLimits(plan, *table, section);
  spec.fingerprint = RiskFingerprint(study, spec);
  return spec;
}

namespace {

// Landings per lane in a group of a batch flown in lanes: as the sweep's groups (16 per lane), so
// that the lanes idle only at a group's end.
constexpr int kGroupLandingsPerLane = 16;

/// A thread's run state: the runner's workspace and a result block (one row, or a group's rows).
struct FlightWorkspace {
  explicit FlightWorkspace(const SweepPlan& plan) : workspace(plan) { block.Allocate(plan); }
  RunWorkspace workspace;
  ResultBlock block;
};

// Rows [0, rows) of `block` ready for their runs: results NaN, status pending.
void ClearRows(const SweepPlan& plan, ResultBlock& block, int rows) {
  block.rows = rows;
  for (std::size_t c = 0; c < block.results.size(); ++c) {
    const auto width = static_cast<std::ptrdiff_t>(plan.schema().columns[c].doubles_per_run());
    std::fill(block.results[c].begin(), block.results[c].begin() + width * rows, kNaN);
  }
  for (int r = 0; r < rows; ++r)
    block.status[static_cast<std::size_t>(r)] = static_cast<std::int8_t>(RunStatus::kPending);
}

// The evaluation of row `row` of `block` (a column's value of the row: its first double).
Evaluation EvaluationOf(const SweepPlan& plan, const ResultBlock& block, int row, int limit,
                        const RiskSpec& spec) {
  const auto r = static_cast<std::size_t>(row);
  Evaluation e;
  e.status = block.status[r];
  e.message = block.message[r];
  for (const int c : RiskColumns(plan)) {
    const auto width =
        static_cast<std::size_t>(plan.schema().columns[static_cast<std::size_t>(c)].doubles_per_run());
    e.values.push_back(block.results[static_cast<std::size_t>(c)][r * width]);
  }
  e.g = kNaN;
  if (limit >= 0 && e.status == static_cast<std::int8_t>(RunStatus::kOk)) {
    const RiskLimit& l = spec.limits[static_cast<std::size_t>(limit)];
    const auto width = static_cast<std::size_t>(
        plan.schema().columns[static_cast<std::size_t>(l.column_index)].doubles_per_run());
    const double x = block.results[static_cast<std::size_t>(l.column_index)][r * width];
    if (std::isfinite(x)) e.g = l.above ? l.value - x : x - l.value;
  }
  return e;
}

Evaluation Fly(const SweepPlan& plan, FlightWorkspace& w, std::int64_t cell, int limit, const RiskSpec& spec,
               std::span<const double> point, const std::atomic<bool>* cancel) {
  ClearRows(plan, w.block, 1);
  ExecuteCellRun(plan, cell, w.workspace, w.block, point, cancel);
  return EvaluationOf(plan, w.block, 0, limit, spec);
}

// The block's rows made at least `rows` (a risk plan's chunk_runs is its cell count, often 1).
void GrowRows(const SweepPlan& plan, ResultBlock& block, int rows) {
  const auto n = static_cast<std::size_t>(rows);
  if (block.status.size() >= n) return;
  block.design_index.resize(n);
  block.run_id.resize(n);
  block.status.resize(n);
  block.message.resize(n);
  for (auto& column : block.design) column.resize(n);
  for (std::size_t c = 0; c < block.results.size(); ++c) {
    block.results[c].resize(n * static_cast<std::size_t>(plan.schema().columns[c].doubles_per_run()));
  }
}

// The landings of `cell` at `points` flown as one group in `lanes` SIMD lanes (ExecuteRuns), each
// evaluation bit for bit Fly's.
std::vector<Evaluation> FlyGroup(const SweepPlan& plan, FlightWorkspace& w, std::int64_t cell, int limit,
                                 const RiskSpec& spec, std::span<const std::span<const double>> points,
                                 int lanes, const std::atomic<bool>* cancel) {
  const int count = static_cast<int>(points.size());
  GrowRows(plan, w.block, count);
  ClearRows(plan, w.block, count);
  const auto random = CellRandomParameters(plan);
  // As ExecuteCellRun splits each point: its noise part, and the random parameters' values.
  std::vector<std::span<const double>> noise(points.begin(), points.end());
  std::vector<std::vector<double>> values;
  std::vector<std::span<const double>> design;
  if (!random.empty()) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      GESWEEP_DEMAND(points[i].size() >= random.size());
      const std::size_t n = points[i].size() - random.size();
      noise[i] = points[i].first(n);
      values.push_back(RandomParameterValues(plan, points[i].subspan(n)));
    }
    design.assign(values.begin(), values.end());
  }
  for (int r = 0; r < count; ++r) w.block.design_index[static_cast<std::size_t>(r)] = cell;
  ExecuteRuns(plan, w.workspace, w.block, 0, count, lanes, cancel, noise, design);
  std::vector<Evaluation> made;
  for (int r = 0; r < count; ++r) made.push_back(EvaluationOf(plan, w.block, r, limit, spec));
  return made;
}

// What one batch of a (cell, limit, repetition) simulation is flown with.
struct BatchContext {
  const SweepPlan& plan;
  const RiskSpec& spec;
  const RiskRunOptions& options;
  tbb::enumerable_thread_specific<FlightWorkspace>& workspaces;
  std::mutex& capture_mutex;
  /// Landings dealt to the processes so far in the run (the same count on every process): a batch's
  /// k-th landing not in the cache goes to process (dealt + k) mod ranks, so that batches smaller
  /// than the ranks still spread evenly over the run.
  std::int64_t& dealt;
  std::int64_t cell;
  int limit;
  int repetition;
};

// A batch's landings: each taken from the cache (a resume, a replay) or flown (fresh), whether the
// replay's point was among them, and whether the batch stops the run (a stop asked of this process,
// or with an exchange of any; a divergence of the processes' points).
struct FlownBatch {
  std::vector<Evaluation> made;
  std::vector<char> fresh;
  bool captured = false;
  bool stop = false;
  std::string diverged;
  std::int64_t flown_here = 0;  ///< complete landings this process flew
};

EvaluationKey KeyOf(const BatchContext& c, const rare::EvaluationTag& tag) {
  return EvaluationKey{
      static_cast<std::int32_t>(c.cell), c.limit, c.repetition, tag.level, tag.chain, tag.step};
}

// A hash of one point's coordinates, bit for bit (FNV-1a over 64-bit words).
std::uint64_t PointHash(std::span<const double> point) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const double v : point) hash = (hash ^ std::bit_cast<std::uint64_t>(v)) * 0x100000001b3ULL;
  return hash;
}

// Every process's share of the batch to every process (BatchExchange): its stop flag, the hash of the
// points it proposed, and the landings it flew (those of `owner` equal to its rank, in batch order).
void ShareBatch(const BatchContext& c, const rare::PointBatch& batch, const std::vector<int>& owner,
                std::uint64_t points_hash, FlownBatch& out) {
  BatchExchange& exchange = *c.options.exchange;
  std::vector<Evaluation> mine;
  for (std::size_t i = 0; i < batch.size(); ++i)
    if (owner[i] == exchange.rank()) mine.push_back(out.made[i]);
  std::vector<unsigned char> bytes(1 + sizeof points_hash);
  bytes[0] = c.options.cancel != nullptr && c.options.cancel->load() ? 1 : 0;
  std::memcpy(bytes.data() + 1, &points_hash, sizeof points_hash);
  const std::vector<unsigned char> records = EncodeEvaluations(mine);
  bytes.insert(bytes.end(), records.begin(), records.end());
  const std::vector<std::vector<unsigned char>> all = exchange.AllGather(bytes);
  GESWEEP_DEMAND(static_cast<int>(all.size()) == exchange.ranks());
  const auto value_count = static_cast<std::uint32_t>(RiskColumns(c.plan).size());
  for (int r = 0; r < exchange.ranks(); ++r) {
    const std::vector<unsigned char>& theirs = all[static_cast<std::size_t>(r)];
    GESWEEP_DEMAND(theirs.size() >= 1 + sizeof points_hash);
    out.stop = out.stop || theirs[0] != 0;
    if (std::memcmp(theirs.data() + 1, bytes.data() + 1, sizeof points_hash) != 0) {
      out.diverged = "process " + std::to_string(r) + " proposed other points than process " +
                     std::to_string(exchange.rank()) + " at level " + std::to_string(batch.tags[0].level) +
                     " of cell " + std::to_string(c.cell) + ", limit " + std::to_string(c.limit);
      continue;
    }
    std::vector<Evaluation> flown;
    GESWEEP_DEMAND(DecodeEvaluations(std::span(theirs).subspan(1 + sizeof points_hash), value_count, flown));
    std::size_t next = 0;
    for (std::size_t i = 0; i < batch.size(); ++i) {
      if (owner[i] != r) continue;
      GESWEEP_DEMAND(next < flown.size() && flown[next].key == KeyOf(c, batch.tags[i]));
      if (r != exchange.rank()) out.made[i] = std::move(flown[next]);
      out.fresh[i] = 1;
      ++next;
    }
    GESWEEP_DEMAND(next == flown.size());
  }
  if (!out.diverged.empty()) out.stop = true;
}

// FlyBatch's landings in groups of lanes: this process's uncached points of `batch` (owner `rank`),
// a group per thread at least (a level's batches are small: N·p0 chains), of a lane width or more
// and at most `group` landings, each group flown by FlyGroup.
void FlyOwnInGroups(const BatchContext& c, const rare::PointBatch& batch,
                    std::span<const Evaluation* const> cached, std::span<const int> owner, int rank,
                    int group, FlownBatch& out) {
  const RiskRunOptions& options = c.options;
  std::vector<std::size_t> mine;
  for (std::size_t i = 0; i < batch.size(); ++i) {
    if (cached[i] == nullptr && owner[i] == rank) mine.push_back(i);
  }
  const auto threads = static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  const std::size_t size =
      std::clamp((mine.size() + threads - 1) / threads, static_cast<std::size_t>(options.lanes),
                 static_cast<std::size_t>(group));
  const std::size_t groups = (mine.size() + size - 1) / size;
  tbb::parallel_for(std::size_t{0}, groups, [&](std::size_t g) {
    const std::size_t begin = g * size;
    const std::size_t end = std::min(mine.size(), begin + size);
    std::vector<std::span<const double>> points;
    for (std::size_t j = begin; j < end; ++j) points.push_back(batch.point(mine[j]));
    std::vector<Evaluation> made = FlyGroup(c.plan, c.workspaces.local(), c.cell, c.limit, c.spec, points,
                                            options.lanes, options.cancel);
    for (std::size_t j = begin; j < end; ++j) {
      const std::size_t i = mine[j];
      out.made[i] = std::move(made[j - begin]);
      out.made[i].key = KeyOf(c, batch.tags[i]);
      out.fresh[i] = 1;
    }
  });
}

// Flies (or takes from the cache) every point of `batch` in parallel, writing each g into `values`.
// With an exchange this process flies only its share of the points not in the cache (the k-th on
// process (dealt + k) mod ranks) and receives the others' (ShareBatch).
FlownBatch FlyBatch(const BatchContext& c, const rare::PointBatch& batch, std::span<double> values) {
  FlownBatch out;
  out.made.resize(batch.size());
  out.fresh.assign(batch.size(), 0);
  const RiskRunOptions& options = c.options;
  const int ranks = options.exchange != nullptr ? options.exchange->ranks() : 1;
  const int rank = options.exchange != nullptr ? options.exchange->rank() : 0;
  std::vector<const Evaluation*> cached(batch.size(), nullptr);
  std::vector<int> owner(batch.size(), -1);  // -1: from the cache
  std::int64_t uncached = 0;
  for (std::size_t i = 0; i < batch.size(); ++i) {
    if (options.cache != nullptr) {
      const auto found = options.cache->find(KeyOf(c, batch.tags[i]));
      if (found != options.cache->end()) cached[i] = &found->second;
    }
    if (cached[i] == nullptr) owner[i] = static_cast<int>((c.dealt + uncached++) % ranks);
  }
  c.dealt += uncached;
  std::atomic<bool> captured{false};
  std::vector<std::uint64_t> hashes(options.exchange != nullptr ? batch.size() : 0);
  // This process's landings of the batch, flown one at a time or in groups of lanes (FlyGroup).
  const int group =
      options.lanes > 1 && RunsInLanes(c.plan, options.lanes) ? kGroupLandingsPerLane * options.lanes : 1;
  tbb::parallel_for(std::size_t{0}, batch.size(), [&](std::size_t i) {
    const EvaluationKey key = KeyOf(c, batch.tags[i]);
    if (options.capture && key == *options.capture && options.captured_point != nullptr) {
      const std::lock_guard lock(c.capture_mutex);
      options.captured_point->assign(batch.point(i).begin(), batch.point(i).end());
      captured = true;
    }
    if (!hashes.empty()) hashes[i] = PointHash(batch.point(i));
    if (cached[i] != nullptr) {
      out.made[i] = *cached[i];
    } else if (owner[i] == rank && group == 1) {
      out.made[i] =
          Fly(c.plan, c.workspaces.local(), c.cell, c.limit, c.spec, batch.point(i), options.cancel);
      out.made[i].key = key;
      out.fresh[i] = 1;
    }
  });
  if (group > 1) FlyOwnInGroups(c, batch, cached, owner, rank, group, out);
  out.captured = captured.load();
  for (std::size_t i = 0; i < batch.size(); ++i)
    out.flown_here += owner[i] == rank && out.made[i].status != static_cast<std::int8_t>(RunStatus::kPending);
  if (options.exchange != nullptr) {
    std::uint64_t points_hash = PointHash({});
    for (std::size_t i = 0; i < batch.size(); ++i)
      points_hash =
          (points_hash ^ hashes[i] ^ (static_cast<std::uint64_t>(owner[i] + 1) << 56)) * 0x100000001b3ULL;
    ShareBatch(c, batch, owner, points_hash, out);
  } else {
    out.stop = options.cancel != nullptr && options.cancel->load();
  }
  for (std::size_t i = 0; i < batch.size(); ++i) values[i] = out.made[i].g;
  return out;
}

// A flown batch's end: its fresh landings journaled (on_batch), and either the run stopped (a stop,
// a landing the flag cut short, a divergence: Cancelled; a replay's point reached: Captured) or its
// landings appended to the run's. A landing the flag stopped is no evaluation: it is neither kept
// nor journaled, and the simulation stops after the complete ones are. (With an exchange every
// process has every landing of the batch and every process's flag, so all stop at the same batch.)
void KeepBatch(FlownBatch flown, const RiskRunOptions& options, RiskRun& run) {
  run.flown_here += flown.flown_here;
  bool stopped = flown.stop;
  std::vector<Evaluation> journal;
  for (std::size_t i = 0; i < flown.made.size(); ++i) {
    if (flown.made[i].status == static_cast<std::int8_t>(RunStatus::kPending)) {
      stopped = true;
      continue;
    }
    if (flown.fresh[i]) journal.push_back(flown.made[i]);
  }
  if (!flown.diverged.empty()) {
    run.diverged = flown.diverged;
    throw Cancelled{};
  }
  if (options.on_batch && !journal.empty()) options.on_batch(journal);
  if (stopped) throw Cancelled{};
  if (flown.captured) throw Captured{};
  for (auto& e : flown.made) run.evaluations.push_back(std::move(e));
}

}  // namespace

Evaluation FlyPoint(const SweepPlan& plan, std::int64_t cell, int limit, const RiskSpec& spec,
                    std::span<const double> point, const std::atomic<bool>* cancel) {
  FlightWorkspace w(plan);
  return Fly(plan, w, cell, limit, spec, point, cancel);
}

RiskRun RunRisk(const SweepPlan& plan, const RiskSpec& spec, const RiskRunOptions& options) {
  RiskRun run;
  tbb::enumerable_thread_specific<FlightWorkspace> workspaces([&] { return FlightWorkspace(plan); });
  std::mutex capture_mutex;
  std::int64_t dealt = 0;
  try {
    for (std::int64_t cell = 0; cell < CellCount(plan); ++cell) {
      const std::uint64_t dimension = CellDimension(plan, cell);
      for (int limit = 0; limit < static_cast<int>(spec.limits.size()); ++limit) {
        LimitRisk risk;
        risk.cell = cell;
        risk.limit = limit;
        risk.dimension = dimension;
        std::vector<rare::SubsetResult> runs;
        for (int repetition = 0; repetition < spec.repetitions; ++repetition) {
          if (options.only && *options.only != std::tuple<std::int64_t, int, int>{cell, limit, repetition})
            continue;
          rare::SubsetOptions subset = spec.subset;
          subset.seed = SimulationSeed(spec.subset.seed, cell, limit, repetition);
          const std::string what = "cell " + std::to_string(cell) + ", " +
                                   spec.limits[static_cast<std::size_t>(limit)].text +
                                   (spec.repetitions > 1 ? ", repetition " + std::to_string(repetition + 1) +
                                                               " of " + std::to_string(spec.repetitions)
                                                         : std::string());
          int last_level = 0;
          const rare::LimitStateBatch g = [&](const rare::PointBatch& batch, std::span<double> values) {
            const BatchContext context{plan,  spec, options, workspaces, capture_mutex,
                                       dealt, cell, limit,   repetition};
            KeepBatch(FlyBatch(context, batch, values), options, run);
            const std::size_t before = run.evaluations.size() - batch.size();
            if (!batch.tags.empty() && batch.tags[0].level != last_level) {
              if (options.progress && last_level > 0) {
                options.progress(what + ": level " + std::to_string(last_level) + " done, " +
                                 std::to_string(before) + " landings so far");
              }
              last_level = batch.tags[0].level;
            }
          };
          runs.push_back(rare::RunSubsetSimulation(g, static_cast<int>(dimension), subset));
          if (repetition == 0 && runs.back().failure_count > 0) {
            const auto& t = runs.back().most_likely_failure_tag;
            const EvaluationKey key{static_cast<std::int32_t>(cell), limit, 0, t.level, t.chain, t.step};
            for (std::size_t r = 0; r < run.evaluations.size(); ++r) {
              if (run.evaluations[r].key == key) risk.most_likely_row = static_cast<std::int64_t>(r);
            }
          }
        }
        if (runs.empty()) continue;
        risk.pooled = rare::PoolRepetitions(runs);
        risk.subset = std::move(runs.front());
        for (std::size_t r = 1; r < runs.size(); ++r) risk.other_repetitions.push_back(std::move(runs[r]));
        run.results.push_back(std::move(risk));
      }
    }
  } catch (const Cancelled&) {
    run.cancelled = true;
  } catch (const Captured&) {
  }
  return run;
}

std::vector<ExceedancePoint> ExceedanceCurve(const LimitRisk& risk, const RiskLimit& limit) {
  std::vector<ExceedancePoint> curve;
  double product = 1, variance = 0;
  const auto& levels = risk.subset.levels;
  for (std::size_t j = 0; j < levels.size(); ++j) {
    product *= levels[j].conditional_probability;
    variance += levels[j].coefficient_of_variation * levels[j].coefficient_of_variation;
    ExceedancePoint point;
    // g = limit − x above a limit (x − limit below it): the level's threshold b_j is x = limit ∓ b_j.
    point.value = limit.above ? limit.value - levels[j].threshold : limit.value + levels[j].threshold;
    point.probability = product;
    point.coefficient_of_variation = std::sqrt(variance);
    rare::LognormalInterval95(point.probability, point.coefficient_of_variation, point.low, point.high);
    curve.push_back(point);
  }
  return curve;
}

}  // namespace gesweep::risk
