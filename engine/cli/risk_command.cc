// gesweep risk: the landing risk by subset simulation (docs/dispersion.md, "Landing risk by subset
// simulation").
//   gesweep risk STUDY -o ARCHIVE [--threads N] [--resume] [--force] [--format table|json] [-q]
//   mpirun -n R gesweep risk STUDY -o ARCHIVE --mpi [--threads N] ...   (the same archive, bit for bit)
//   gesweep risk ARCHIVE --replay ROW [--format table|json]
// STUDY has a [subset] table (the limits and the method). The run journals every batch of landings
// (ARCHIVE.journal) so that a killed run resumes with --resume to the same estimate bit for bit; the
// archive is written whole at the end. --replay flies one stored landing again from the archive
// alone (its recipe: the study, the tag and the values before it) and compares it bit for bit.
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "engine/archive/archive_lock.h"
#include "engine/archive/provenance.h"
#include "engine/cli/command.h"
#include "engine/cli/failure_text.h"
#include "engine/cli/json_util.h"
#include "engine/cli/model_flags.h"
#include "engine/cli/risk_output.h"
#include "engine/cli/signals.h"
#include "engine/common/errors.h"
#include "engine/common/output_guard.h"
#include "engine/disturbance/run_noise.h"
#include "engine/risk/risk_archive.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#ifdef GESWEEP_HAVE_MPI
#include "engine/mpi/mpi_runner.h"
#include "engine/mpi/risk_exchange.h"
#endif

namespace gesweep::cli {
namespace {

using nlohmann::ordered_json;
using risk::Evaluation;
using risk::EvaluationKey;

/// A number, or null when it is not finite (JsonNumber's rule, in an ordered document).
ordered_json Num(double value) { return std::isfinite(value) ? ordered_json(value) : ordered_json(nullptr); }

struct RiskFlags {
  std::string input;
  std::string output;
  std::optional<int> threads;
  std::optional<long long> replay;
  TableOrJson format = TableOrJson::kAligned;
  bool resume = false;
  bool force = false;
  bool quiet = false;
  bool mpi = false;
  int lanes = DefaultLanes();
  DescribedFlags described{{{"quiet", "-q"}}};

  template <class V>
  void Describe(V& v) {
    v(Field("resume", &resume)
          .Doc("Continue an interrupted run from its journal (ARCHIVE.journal): the same estimate bit for "
               "bit"));
    v(Field("lanes", &lanes)
          .Limit("lanes")
          .Doc("Landings of a batch flown at once in SIMD lanes (turbulent landings flown by RK4): 1, 2, 4 "
               "or 8; 1 is one at a time. The archive is the same bit for bit whatever it is"));
    v(Field("force", &force)
          .Doc("Replace an existing archive (and discard the journal of an interrupted run)"));
    v(Field("quiet", &quiet).Doc("No progress lines"));
    v(Field("mpi", &mpi)
          .Doc("Spread each batch of landings over MPI ranks: mpirun -n R gesweep risk ... --mpi (the same "
               "archive as one process, bit for bit)"));
    v(Field("format", &format).Doc("Output: the estimates as a table, or the archive's result JSON"));
  }
};

std::string CommandLine(const RiskFlags& flags) {
  std::string line = "gesweep risk " + flags.input;
  if (!flags.output.empty()) line += " -o " + flags.output;
  if (flags.threads) line += " --threads " + std::to_string(*flags.threads);
  if (flags.resume) line += " --resume";
  if (flags.force) line += " --force";
  if (flags.mpi) line += " --mpi";
  if (flags.lanes != DefaultLanes()) line += " --lanes " + std::to_string(flags.lanes);
  return line;
}

// A subset result's status in the JSON and the table.
const char* StatusName(rare::SubsetResult::Status status) {
  return status == rare::SubsetResult::Status::kConverged  ? "converged"
         : status == rare::SubsetResult::Status::kLevelCap ? "level_cap"
                                                           : "too_many_failed_runs";
}

// A run of more than two levels whose last level descends from fewer than a tenth of the chains
// (N p0 of them).
bool Collapsed(const risk::RiskSpec& spec, const rare::SubsetResult& run) {
  const long long chains = std::llround(spec.subset.samples_per_level * spec.subset.level_probability);
  return run.levels.size() > 2 && run.levels.back().ancestors * 10 < chains;
}

// How many of a limit's K repetitions collapsed.
int CollapsedRuns(const risk::RiskSpec& spec, const risk::LimitRisk& r) {
  int count = Collapsed(spec, r.subset) ? 1 : 0;
  for (const auto& other : r.other_repetitions) count += Collapsed(spec, other) ? 1 : 0;
  return count;
}

// The K repetitions of one estimate: each run's seed, status, estimate and lineage.
ordered_json RepetitionsJson(const risk::RiskSpec& spec, const risk::LimitRisk& r) {
  const auto& pooled = r.pooled;
  ordered_json repetitions;
  repetitions["count"] = pooled.repetitions;
  repetitions["measured_coefficient_of_variation_one_run"] =
      Num(pooled.measured_coefficient_of_variation_one_run);
  repetitions["mean_stated_coefficient_of_variation"] = Num(pooled.mean_stated_coefficient_of_variation);
  ordered_json estimates = ordered_json::array();
  const auto estimate = [&](int repetition, const rare::SubsetResult& run) {
    estimates.push_back({{"repetition", repetition},
                         {"seed", risk::SimulationSeed(spec.subset.seed, r.cell, r.limit, repetition)},
                         {"status", StatusName(run.status)},
                         {"probability", Num(run.probability)},
                         {"coefficient_of_variation", Num(run.coefficient_of_variation)},
                         {"interval_95", {Num(run.interval_95_low), Num(run.interval_95_high)}},
                         {"levels", run.levels.size()},
                         {"runs", run.evaluations},
                         {"last_level_ancestors", run.levels.empty() ? 0 : run.levels.back().ancestors},
                         {"collapsed", Collapsed(spec, run)}});
  };
  estimate(0, r.subset);
  for (std::size_t k = 0; k < r.other_repetitions.size(); ++k)
    estimate(static_cast<int>(k + 1), r.other_repetitions[k]);
  repetitions["estimates"] = estimates;
  return repetitions;
}

// The first repetition's levels: the thresholds, each level's figures and the exceedance curve.
void AddLevels(ordered_json& j, const risk::LimitRisk& r, const risk::RiskLimit& limit) {
  const auto& s = r.subset;
  ordered_json thresholds = ordered_json::array(), levels = ordered_json::array();
  const auto curve = risk::ExceedanceCurve(r, limit);
  for (std::size_t k = 0; k < s.levels.size(); ++k) {
    const auto& level = s.levels[k];
    if (k + 1 < s.levels.size()) thresholds.push_back(Num(curve[k].value));
    levels.push_back({{"threshold", Num(curve[k].value)},
                      {"conditional_probability", Num(level.conditional_probability)},
                      {"coefficient_of_variation", Num(level.coefficient_of_variation)},
                      {"correlation_factor", Num(level.correlation_factor)},
                      {"acceptance_rate", Num(level.acceptance_rate)},
                      {"scale", Num(level.scale)},
                      {"runs", level.evaluations},
                      {"failed_runs", level.failed_evaluations},
                      {"ancestors", level.ancestors}});
  }
  j["thresholds"] = thresholds;
  j["last_level_ancestors"] = s.levels.empty() ? 0 : s.levels.back().ancestors;
  j["levels"] = levels;
  ordered_json exceedance = ordered_json::array();
  for (const auto& p : curve) {
    exceedance.push_back({{"value", Num(p.value)},
                          {"probability", Num(p.probability)},
                          {"coefficient_of_variation", Num(p.coefficient_of_variation)},
                          {"interval_95", {Num(p.low), Num(p.high)}}});
  }
  j["exceedance"] = exceedance;
}

// The design point: the failing landings of the last level, the most likely one, and the random
// parameters' values there.
ordered_json DesignPointJson(const SweepPlan& plan, const risk::RiskRun& run, const risk::LimitRisk& r,
                             const risk::RiskLimit& limit) {
  const auto& s = r.subset;
  ordered_json design;
  design["failing_runs_last_level"] = s.failure_count;
  if (r.most_likely_row >= 0) {
    const Evaluation& e = run.evaluations[static_cast<std::size_t>(r.most_likely_row)];
    design["most_likely_row"] = r.most_likely_row;
    design["most_likely_tag"] = {{"level", e.key.level}, {"chain", e.key.chain}, {"step", e.key.step}};
    design["most_likely_value"] = Num(limit.above ? limit.value - e.g : limit.value + e.g);
    double norm2 = 0;
    for (const double v : s.most_likely_failure) norm2 += v * v;
    design["most_likely_distance"] = std::sqrt(norm2);
  }
  // A random parameter's values at the design point: at the most likely failing landing and at the
  // failing landings' mean point (their coordinates come after the noise's), beside its median.
  const auto random = risk::CellRandomParameters(plan);
  if (!random.empty()) {
    const auto at = [&](const std::vector<double>& point) -> std::vector<double> {
      if (point.size() < random.size()) return {};
      return risk::RandomParameterValues(plan, std::span(point).last(random.size()));
    };
    const std::vector<double> origin(random.size(), 0.0);
    const std::vector<double> medians = risk::RandomParameterValues(plan, origin);
    const std::vector<double> likely = at(s.most_likely_failure), mean = at(s.failure_mean);
    ordered_json parameters = ordered_json::array();
    for (std::size_t k = 0; k < random.size(); ++k) {
      parameters.push_back({{"name", ParameterCatalog()[static_cast<std::size_t>(random[k].id)].name},
                            {"distribution", DescribeDistribution(random[k])},
                            {"median", Num(medians[k])},
                            {"most_likely", likely.empty() ? ordered_json(nullptr) : Num(likely[k])},
                            {"mean_failure", mean.empty() ? ordered_json(nullptr) : Num(mean[k])}});
    }
    design["random_parameters"] = parameters;
  }
  return design;
}

ordered_json LimitJson(const SweepPlan& plan, const risk::RiskSpec& spec, const risk::RiskRun& run,
                       const risk::LimitRisk& r) {
  const auto& limit = spec.limits[static_cast<std::size_t>(r.limit)];
  const auto& s = r.subset;
  const auto& pooled = r.pooled;
  ordered_json j;
  j["cell"] = r.cell;
  j["cell_label"] = risk::CellLabel(plan, r.cell);
  j["limit"] = limit.text;
  j["column"] = limit.column;
  j["units"] = limit.units;
  j["above"] = limit.above;
  j["value"] = limit.value;
  // The estimate: the K repetitions pooled (for K = 1 the run's own figures). Levels, thresholds,
  // the exceedance curve and the design point below are the first repetition's.
  j["status"] = StatusName(pooled.status);
  j["probability"] = Num(pooled.probability);
  j["coefficient_of_variation"] = Num(pooled.coefficient_of_variation);
  j["coefficient_of_variation_correlated_levels"] =
      pooled.repetitions == 1 ? Num(s.coefficient_of_variation_upper) : ordered_json(nullptr);
  j["interval_95"] = {Num(pooled.interval_95_low), Num(pooled.interval_95_high)};
  j["upper_bound"] = pooled.status == rare::SubsetResult::Status::kLevelCap ? Num(pooled.upper_bound)
                                                                            : ordered_json(nullptr);
  j["runs"] = pooled.evaluations;
  j["failed_runs"] = pooled.failed_evaluations;
  j["dimension"] = r.dimension;
  j["collapsed_runs"] = CollapsedRuns(spec, r);
  j["repetitions"] = RepetitionsJson(spec, r);
  AddLevels(j, r, limit);
  j["design_point"] = DesignPointJson(plan, run, r, limit);
  return j;
}

// What the archive stores: the estimates, not where the file was written (an archive may be moved or
// merged; 1 and 2 threads, a resumed run and an uninterrupted one store the same bytes).
ordered_json ResultJson(const SweepPlan& plan, const risk::RiskSpec& spec, const risk::RiskRun& run) {
  ordered_json j;
  j["study"] = plan.study().name;
  j["method"] = {{"name", "subset_simulation"},
                 {"sampler", std::string(ToString(spec.subset.sampler))},
                 {"level_probability", spec.subset.level_probability},
                 {"samples_per_level", spec.subset.samples_per_level},
                 {"max_levels", spec.subset.max_levels},
                 {"seed", spec.subset.seed},
                 {"repetitions", spec.repetitions}};
  j["runs"] = static_cast<std::int64_t>(run.evaluations.size());
  ordered_json limits = ordered_json::array();
  for (const auto& r : run.results) limits.push_back(LimitJson(plan, spec, run, r));
  j["limits"] = limits;
  return j;
}

/// The landing series of a point, flown on the study with its series stored.
risk::PointSeries FlySeries(const SweepPlan& series_plan, std::int64_t cell, const risk::RiskSpec& spec,
                            std::span<const double> point, const std::string& name) {
  RunWorkspace workspace(series_plan);
  ResultBlock block;
  block.Allocate(series_plan);
  block.Reset(series_plan, 0);
  risk::ExecuteCellRun(series_plan, cell, workspace, block, point);
  (void)spec;
  risk::PointSeries series;
  series.name = name;
  const auto& schema = series_plan.schema();
  for (std::size_t c = 0; c < schema.columns.size(); ++c) {
    const auto& column = schema.columns[c];
    if (column.time_axis.empty()) continue;
    if (series.time_s.empty()) {
      for (const auto& axis : schema.axes) {
        if (axis.path == column.time_axis) series.time_s = axis.times_s;
      }
    }
    series.columns.push_back(column.path.substr(column.path.rfind('/') + 1));
    series.units.push_back(column.units);
    const double* values = block.results[c].data();
    series.values.emplace_back(values, values + column.width);
  }
  return series;
}

std::vector<risk::DesignPoint> DesignPoints(const SweepPlan& plan, const risk::RiskSpec& spec,
                                            const risk::RiskRun& run) {
  Study study = ParseStudy(plan.study().text, plan.study().path);
  study.storage.time_series = true;
  const SweepPlan series_plan(std::move(study), ShardSpec{});
  std::vector<risk::DesignPoint> points;
  for (const auto& r : run.results) {
    risk::DesignPoint point;
    point.cell = r.cell;
    point.limit = r.limit;
    point.sample_interval_s = risk::CellSampleInterval(plan, r.cell);
    point.mean_noise = r.subset.failure_mean;
    point.most_likely_noise = r.subset.most_likely_failure;
    const std::vector<double> zero(r.dimension, 0.0);
    point.series.push_back(FlySeries(series_plan, r.cell, spec, zero, "steady"));
    if (!point.mean_noise.empty()) {
      point.series.push_back(FlySeries(series_plan, r.cell, spec, point.mean_noise, "mean_failure"));
      point.series.push_back(FlySeries(series_plan, r.cell, spec, point.most_likely_noise, "most_likely"));
    }
    points.push_back(std::move(point));
  }
  return points;
}

// --threads is checked against the limits table by its validator (AddRiskFlags).
int Replay(const RiskFlags& flags) {
  if (!flags.output.empty() || flags.resume || flags.force) {
    throw InputError("command line", "--replay", std::to_string(*flags.replay),
                     "without -o, --resume or --force: a replay reads the archive and writes nothing");
  }
  return GuardArchive([&] {
    RequireRegularFile(flags.input, "archive");
    const risk::RiskArchive archive = risk::ReadRiskArchive(flags.input, false);
    const auto rows = static_cast<long long>(archive.evaluations.size());
    if (*flags.replay < 0 || *flags.replay >= rows) {
      throw InputError("command line", "--replay", std::to_string(*flags.replay),
                       "a row of the archive's evaluations, 0 to " + std::to_string(rows - 1));
    }
    Study study = ParseStudy(archive.study_text, archive.study_path);
    const SweepPlan plan(std::move(study), ShardSpec{});
    const risk::RiskSpec spec = risk::ReadRiskSpec(plan);
    if (spec.fingerprint != archive.fingerprint) {
      throw InputError(
          flags.input, "spec_fingerprint", "",
          "the study as this engine reads it now: its fingerprint differs from the archive's "
          "(another engine, or a changed aircraft file), so a replay would not fly the same landings");
    }
    std::map<EvaluationKey, Evaluation> cache;
    for (const auto& e : archive.evaluations) cache.emplace(e.key, e);
    const Evaluation& stored = archive.evaluations[static_cast<std::size_t>(*flags.replay)];
    std::vector<double> point;
    risk::RiskRunOptions options;
    options.cache = &cache;
    options.capture = stored.key;
    options.captured_point = &point;
    options.only =
        std::tuple<std::int64_t, int, int>{stored.key.cell, stored.key.limit, stored.key.repetition};
    (void)risk::RunRisk(plan, spec, options);
    if (point.empty()) {
      throw InputError(flags.input, "", "",
                       "evaluations that reach row " + std::to_string(*flags.replay) +
                           ": the subset simulation over the stored values never proposes it");
    }
    const Evaluation flown = risk::FlyPoint(plan, stored.key.cell, stored.key.limit, spec, point);
    bool identical = std::bit_cast<std::uint64_t>(flown.g) == std::bit_cast<std::uint64_t>(stored.g) &&
                     flown.status == stored.status && flown.values.size() == stored.values.size();
    for (std::size_t k = 0; identical && k < flown.values.size(); ++k) {
      identical =
          std::bit_cast<std::uint64_t>(flown.values[k]) == std::bit_cast<std::uint64_t>(stored.values[k]);
    }
    ordered_json j;
    j["archive"] = flags.input;
    j["row"] = *flags.replay;
    j["cell"] = stored.key.cell;
    j["limit"] = stored.key.limit;
    j["repetition"] = stored.key.repetition;
    j["level"] = stored.key.level;
    j["chain"] = stored.key.chain;
    j["step"] = stored.key.step;
    j["identical"] = identical;
    j["g"] = Num(flown.g);
    j["stored_g"] = Num(stored.g);
    ordered_json values;
    for (std::size_t k = 0; k < flown.values.size(); ++k) {
      const std::string& path = archive.value_columns[k];
      values[path.substr(path.rfind('/') + 1)] = Num(flown.values[k]);
    }
    j["values"] = values;
    if (flags.format == TableOrJson::kJson) {
      std::cout << j.dump(2) << "\n";
    } else {
      std::cout << "row " << *flags.replay << " (cell " << stored.key.cell << ", limit " << stored.key.limit
                << ", repetition " << stored.key.repetition << ", level " << stored.key.level << ", chain "
                << stored.key.chain << ", step " << stored.key.step
                << "): " << (identical ? "identical to the archive, bit for bit" : "DIFFERS from the archive")
                << "\n";
    }
    if (!identical) {
      std::cerr << "gesweep: the replay of row " << *flags.replay << " differs from the archive's values\n";
      return 1;
    }
    return 0;
  });
}

// What -o, --resume and --force ask of the archive and its journal (refused with one line
// otherwise); whether the journal exists.
bool CheckRiskOutputs(const RiskFlags& flags, const std::filesystem::path& output,
                      const std::filesystem::path& journal) {
  const bool output_exists = std::filesystem::exists(output);
  const bool journal_exists = std::filesystem::exists(journal);
  if (flags.resume && !journal_exists) {
    throw InputError("command line", "--resume", "",
                     output_exists ? "a run to resume: " + output.string() + " is complete (no journal)"
                                   : "a journal " + journal.string() + " to resume from: there is none");
  }
  if (!flags.resume && !flags.force && output_exists) {
    throw InputError("command line", "-o", output.string(), "a new archive: it exists (--force replaces it)");
  }
  if (!flags.resume && !flags.force && journal_exists) {
    throw InputError("command line", "-o", output.string(),
                     "no interrupted run: " + journal.string() +
                         " holds one (--resume continues it, --force starts over)");
  }
  return journal_exists;
}

// What a run needs before its first landing: the plan and the spec (on every process), and on the
// process that writes (the only one, or MPI rank 0) the archive's lock, the journal read back (the
// resume's landings: `cache`) and its writer.
struct RiskSetup {
  std::unique_ptr<SweepPlan> plan;
  risk::RiskSpec spec;
  std::optional<ArchiveLock> lock;
  std::map<EvaluationKey, Evaluation> cache;
  std::int64_t resumed_records = 0;
  bool torn_tail = false;
  std::unique_ptr<risk::JournalWriter> journal;
};

// Reads the study and its [subset] table into `s`; with `writes`, also checks -o, --resume and
// --force against the files there, takes the lock and opens the journal. Throws InputError (a
// person's mistake) or ArchiveError.
void SetUpRisk(const RiskFlags& flags, bool writes, RiskSetup& s) {
  if (std::ranges::find(kLaneWidths, flags.lanes) == std::end(kLaneWidths)) {
    throw InputError("command line", "--lanes", std::to_string(flags.lanes), "expected 1, 2, 4 or 8 lanes");
  }
  if (flags.replay) {
    throw InputError("command line", "--mpi", "",
                     "not with --replay: a replay flies one landing, in one process (leave out --mpi)");
  }
  Study study = LoadStudy(flags.input);
  if (flags.output.empty()) {
    throw InputError("command line", "-o", "",
                     "missing: the archive to write, e.g. -o results/landing_risk.h5");
  }
  const std::filesystem::path output(flags.output), journal = risk::JournalPath(output);
  const std::filesystem::path partial(output.string() + ".partial");
  if (writes) {
    CheckOutputPath(output, OutputKind::kFile, study.inputs, "-o", {journal, partial});
    RequireOutputDirectory(output, "-o");
  }
  if (flags.resume && flags.force) {
    throw InputError("command line", "--resume", "", "not with --force: resume a run, or start it over");
  }
  s.plan = std::make_unique<SweepPlan>(std::move(study), ShardSpec{});
  s.spec = risk::ReadRiskSpec(*s.plan);
  if (!writes) return;
  const auto value_count = static_cast<std::uint32_t>(risk::RiskColumns(*s.plan).size());
  s.lock.emplace(ArchiveLock::AcquireOutput(output, "-o"));
  const bool journal_exists = CheckRiskOutputs(flags, output, journal);
  std::uint64_t resume_length = 0;
  if (flags.resume) {
    risk::JournalContents resumed = risk::ReadJournal(journal, s.spec.fingerprint, value_count);
    s.cache = std::move(resumed.evaluations);
    s.resumed_records = resumed.records;
    s.torn_tail = resumed.torn_tail;
    resume_length = resumed.valid_length;
  } else if (journal_exists) {
    std::filesystem::remove(journal);
  }
  s.journal = std::make_unique<risk::JournalWriter>(journal, s.spec.fingerprint, value_count, resume_length);
}

// The collectives around a run on MPI ranks (none for one process): the batches' exchange, the
// largest of the ranks' values, and rank 0's value on every rank.
struct RiskProcesses {
  risk::BatchExchange* exchange = nullptr;
  std::function<std::int64_t(std::int64_t)> max;
  std::function<int(int)> from_rank0;
  bool speaks() const { return exchange == nullptr || exchange->rank() == 0; }
};

// The finished run's archive (written whole, then the journal removed) and its table or JSON.
void WriteRiskOutputs(const RiskFlags& flags, const RiskSetup& s, risk::RiskRun& run) {
  const SweepPlan& plan = *s.plan;
  const std::filesystem::path output(flags.output);
  risk::RiskArchive archive;
  archive.study_path = plan.study().path;
  archive.study_text = plan.study().text;
  archive.fingerprint = s.spec.fingerprint;
  archive.command_line = CommandLine(flags);
  archive.result_json = ResultJson(plan, s.spec, run).dump(2);
  for (const int c : risk::RiskColumns(plan))
    archive.value_columns.push_back(plan.schema().columns[static_cast<std::size_t>(c)].path);
  archive.evaluations = std::move(run.evaluations);
  archive.design_points = DesignPoints(plan, s.spec, run);
  risk::WriteRiskArchive(output, archive);
  std::filesystem::remove(risk::JournalPath(output));
  if (flags.format == TableOrJson::kJson) {
    std::cout << WithArchive(archive.result_json, output) << "\n";
  } else {
    PrintRiskTable(archive.result_json);
    std::cout << "# written to " << output.string() << " (" << archive.evaluations.size() << " landings)\n";
  }
}

// On MPI ranks, rank 0's line of how the landings were spread: "gesweep: 940 landings flown on 3 MPI
// ranks (landings per rank: 314 313 313)". Collective.
void ReportRanks(const RiskFlags& flags, const risk::RiskRun& run, risk::BatchExchange& exchange) {
  std::vector<unsigned char> mine(sizeof run.flown_here);
  std::memcpy(mine.data(), &run.flown_here, sizeof run.flown_here);
  const std::vector<std::vector<unsigned char>> all = exchange.AllGather(mine);
  if (exchange.rank() != 0 || flags.quiet) return;
  std::int64_t total = 0;
  std::string per_rank;
  for (const auto& bytes : all) {
    std::int64_t flown = 0;
    std::memcpy(&flown, bytes.data(), std::min(bytes.size(), sizeof flown));
    total += flown;
    per_rank += " " + std::to_string(flown);
  }
  std::cerr << "gesweep: " << total << " landings flown on " << all.size()
            << " MPI ranks (landings per rank:" << per_rank << ")\n";
}

// Runs the subset simulations (every process alike) and, on the process that speaks, writes the
// archive; the exit code, the same on every process: 0, 1 (the archive could not be written, or the
// ranks diverged), or 128 + the signal that stopped the run (the journal kept for --resume).
int FlyRisk(const RiskFlags& flags, RiskSetup& s, const RiskProcesses& processes) {
  const bool speaks = processes.speaks();
  const std::filesystem::path journal = risk::JournalPath(flags.output);
  if (flags.resume && speaks && !flags.quiet) {
    std::cerr << "gesweep: resuming from " << journal.string() << ": " << s.resumed_records << " landings"
              << (s.torn_tail ? " (a torn last record dropped)" : "") << "\n";
  }
  SignalCancellation signals;
  risk::RiskRunOptions options;
  options.lanes = flags.lanes;
  options.cancel = signals.flag();
  options.cache = flags.resume ? &s.cache : nullptr;
  options.exchange = processes.exchange;
  if (s.journal) options.on_batch = [&](std::span<const Evaluation> batch) { s.journal->Append(batch); };
  if (speaks && !flags.quiet)
    options.progress = [](const std::string& line) { std::cerr << "gesweep: " << line << "\n"; };
  const int threads = flags.threads.value_or(tbb::info::default_concurrency());
  risk::RiskRun run;
  tbb::task_arena arena(threads);
  arena.execute([&] { run = risk::RunRisk(*s.plan, s.spec, options); });
  // A signal after the last batch stops the run too, on every rank if on any.
  const int signal = static_cast<int>(processes.max ? processes.max(signals.signal()) : signals.signal());
  if (!run.diverged.empty()) {
    if (speaks) {
      std::cerr
          << "gesweep: error: the MPI ranks flew different landings (" << run.diverged
          << "): run them on machines that compute alike, or with one process; the landings made are in "
          << journal.string() << " for --resume\n";
    }
    return 1;
  }
  if (run.cancelled || signal != 0) {
    if (speaks) {
      std::cerr << "gesweep: stopped by signal " << signal << ": the landings made are in "
                << journal.string() << "; `" << CommandLine(flags) << " --resume` continues\n";
    }
    return 128 + signal;
  }
  if (processes.exchange != nullptr) ReportRanks(flags, run, *processes.exchange);
  const int code = speaks ? GuardArchive([&] {
    WriteRiskOutputs(flags, s, run);
    return 0;
  })
                          : 0;
  return processes.from_rank0 ? processes.from_rank0(code) : code;
}

// mpirun -n R gesweep risk STUDY -o ARCHIVE --mpi (docs/dispersion.md, "On MPI ranks"): every rank
// runs the same driver and flies its share of each batch; rank 0 alone reads and writes files and
// prints. A person's mistake on any rank is one line from rank 0, and every rank exits with its code.
int RunRiskMpi(const RiskFlags& flags) {
#ifdef GESWEEP_HAVE_MPI
  MpiFinalizer finalize_after_printing;
  MpiBatchExchange mpi;
  const bool speaks = mpi.rank() == 0;
  RiskSetup setup;
  std::string error, first;
  int code = 0;
  try {
    SetUpRisk(flags, speaks, setup);
  } catch (...) {
    code = FailureLine(std::current_exception(), error);
  }
  if ((code = mpi.AgreeOnError(code, error, &first)) != 0) {
    if (speaks) std::cerr << "gesweep: error: " << first << "\n";
    return code;
  }
  if (!mpi.Same(setup.spec.fingerprint)) {
    if (speaks) {
      std::cerr
          << "gesweep: error: the " << mpi.ranks() << " MPI ranks did not read the same study and "
          << "[subset] table (fingerprints differ): every node must see the same study and aircraft files\n";
    }
    return 2;
  }
  // A resume's landings: rank 0 read them from the journal; every rank takes the same ones.
  std::vector<Evaluation> cached;
  for (const auto& entry : setup.cache) cached.push_back(entry.second);
  const std::vector<unsigned char> bytes = mpi.Broadcast(risk::EncodeEvaluations(cached));
  cached.clear();
  const auto value_count = static_cast<std::uint32_t>(risk::RiskColumns(*setup.plan).size());
  GESWEEP_DEMAND(risk::DecodeEvaluations(bytes, value_count, cached));
  for (auto& e : cached) setup.cache.emplace(e.key, std::move(e));
  RiskProcesses processes{&mpi, [&](std::int64_t v) { return mpi.Max(v); },
                          [&](int v) {
                            const auto from =
                                mpi.Broadcast(std::vector<unsigned char>{static_cast<unsigned char>(v)});
                            return static_cast<int>(from.at(0));
                          }};
  try {
    return FlyRisk(flags, setup, processes);
  } catch (...) {
    // An I/O error of rank 0's journal, or a failure nothing caught: the other ranks may wait in a
    // collective, so every rank is ended; the journal keeps every batch before it.
    code = FailureLine(std::current_exception(), error);
    std::cerr << "gesweep: error: " << error << " (stopping every rank)\n";
    AbortMpi(code);
  }
#else
  (void)flags;
  throw InputError("command line", "--mpi", "", "this gesweep was built without MPI (libopenmpi-dev)");
#endif
}

int RunRiskCommand(const RiskFlags& flags) {
  if (flags.mpi) return RunRiskMpi(flags);
  if (flags.replay) return Replay(flags);
  return GuardArchive([&] {
    RiskSetup setup;
    SetUpRisk(flags, true, setup);
    return FlyRisk(flags, setup, RiskProcesses{});
  });
}

void AddRiskFlags(CLI::App& app, RiskFlags& flags) {
  app.add_option("input", flags.input, "Study with a [subset] table (or, with --replay, its archive)")
      ->required();
  app.add_option("-o,--output", flags.output,
                 "Archive to write (its journal ARCHIVE.journal is kept while the run goes, for --resume)");
  app.add_option("--threads", flags.threads,
                 "Threads (default: every core); the estimate does not depend on them")
      ->check(ExactIntegerValidator("--threads", "threads", std::numeric_limits<int>::max()));
  app.add_option(
         "--replay", flags.replay,
         "Fly row ROW of the archive's evaluations again from the archive alone and compare bit for bit")
      ->check(ExactIntegerValidator("--replay", "run_index",
                                    static_cast<double>(std::numeric_limits<long long>::max())));
}

const CommandRegistrar kRegistrar{CommandWith<RiskFlags>(
    "risk",
    "Landing risk by subset simulation: for each limit of the study's [subset] table, the probability "
    "that a landing in its turbulence exceeds it, with its coefficient of variation and 95 % interval",
    AddRiskFlags, RunRiskCommand)};

}  // namespace

std::string WithArchive(const std::string& result_json, const std::filesystem::path& archive) {
  ordered_json j;
  j["archive"] = archive.string();
  const ordered_json stored = ordered_json::parse(result_json);
  for (const auto& [key, value] : stored.items()) j[key] = value;
  return j.dump(2);
}

void PrintRiskTable(const std::string& result_json) {
  const auto j = nlohmann::json::parse(result_json);
  std::cout << "# subset simulation: " << j["method"]["sampler"].get<std::string>()
            << ", p0 = " << j["method"]["level_probability"].get<double>()
            << ", N = " << j["method"]["samples_per_level"].get<long long>() << " per level, "
            << j["runs"].get<long long>() << " landings\n";
  for (const auto& l : j["limits"]) {
    const auto number = [](const nlohmann::json& v) {
      if (v.is_null()) return std::string("-");
      char text[32];
      std::snprintf(text, sizeof text, "%.3g", v.get<double>());
      return std::string(text);
    };
    const std::string cell = l["cell_label"].get<std::string>();
    std::cout << (cell.empty() ? "" : cell + ": ") << l["limit"].get<std::string>()
              << "  P = " << number(l["probability"]) << "  CoV " << number(l["coefficient_of_variation"])
              << "  95 % [" << number(l["interval_95"][0]) << ", " << number(l["interval_95"][1]) << "]  "
              << l["levels"].size() << (l["levels"].size() == 1 ? " level, " : " levels, ")
              << l["runs"].get<long long>() << " landings (" << l["failed_runs"].get<long long>()
              << " failed)";
    if (l["status"] == "level_cap") std::cout << "  below the level cap: P < " << number(l["upper_bound"]);
    if (l["status"] == "too_many_failed_runs") std::cout << "  too many failed runs for a threshold";
    const long long count = l.contains("repetitions") ? l["repetitions"]["count"].get<long long>() : 1;
    if (count > 1) {
      // K runs: the CoV and the interval are measured from their spread (docs/dispersion.md).
      const auto& reps = l["repetitions"];
      std::cout << "  measured over " << count << " repetitions: one run's CoV "
                << number(reps["measured_coefficient_of_variation_one_run"]) << " (its stated CoV "
                << number(reps["mean_stated_coefficient_of_variation"]) << ")";
      if (l["collapsed_runs"].get<long long>() > 0)
        std::cout << ", " << l["collapsed_runs"].get<long long>() << " collapsed";
      std::cout << "\n";
      continue;
    }
    // The collapse diagnostic (docs/dispersion.md): a last level that descends from fewer than a tenth
    // of the chains' worth of first-level landings is one family, and its CoV is no error bar.
    const long long chains = std::llround(j["method"]["samples_per_level"].get<double>() *
                                          j["method"]["level_probability"].get<double>());
    const long long ancestors = l.value("last_level_ancestors", chains);
    if (l["levels"].size() > 2 && ancestors * 10 < chains) {
      std::cout
          << "  COLLAPSED: the last level descends from " << ancestors
          << " first-level landing(s); the CoV understates the error: measure it with [subset] repetitions";
    }
    std::cout << "\n";
  }
}

int PrintRiskArchive(const std::filesystem::path& path, TableOrJson format) {
  return GuardArchive([&] {
    const risk::RiskArchive archive = risk::ReadRiskArchive(path, false);
    if (format == TableOrJson::kJson) {
      std::cout << WithArchive(archive.result_json, path) << "\n";
    } else {
      PrintRiskTable(archive.result_json);
    }
    return 0;
  });
}

}  // namespace gesweep::cli
