#include "engine/sweep/runner.h"

#include <tbb/concurrent_queue.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "engine/common/errors.h"
#include "engine/simulation/lanes_isa.h"

namespace gesweep {
namespace {

constexpr int kTokensPerThread =
    2;  // batches in flight per worker: keeps every thread busy at a batch's tail

// The model options' parameters by hand (ModelOptions::Describe says why): the scale factors and
// the mass properties.
struct ModelParameterIds {
  ParameterId CDo_scale = RequireParameter("scale.CDo");
  ParameterId mass = RequireParameter("mass_kg");
  ParameterId inertia = RequireParameter("pitch_inertia_kgm2");
  std::array<ParameterId, kCoefficientCount> scale{};
  ModelParameterIds() {
    for (int i = 0; i < kCoefficientCount; ++i) {
      scale[static_cast<std::size_t>(i)] =
          RequireParameter("scale." + std::string(kCoefficientNames[static_cast<std::size_t>(i)]));
    }
  }
};

const ModelParameterIds& ModelIds() {
  static const ModelParameterIds ids;
  return ids;
}

ModelOptions OptionsFrom(const RunParameters& p) {
  const ModelParameterIds& ids = ModelIds();
  auto at = [&](ParameterId id) { return p[static_cast<std::size_t>(id)]; };
  ModelOptions options;
  ApplyRunParameters(p, options);  // the described ones (ModelOptions::Describe)
  for (int i = 0; i < kCoefficientCount; ++i) {
    options.coefficient_scale[static_cast<std::size_t>(i)] = at(ids.scale[static_cast<std::size_t>(i)]);
  }
  options.CDo_scale = at(ids.CDo_scale);
  options.mass_kg = at(ids.mass);
  options.pitch_inertia_kgm2 = at(ids.inertia);
  return options;
}

void AppendMessage(std::string& message, std::string_view analysis, const std::string& text) {
  if (text.empty()) return;
  if (!message.empty()) message += "; ";
  message.append(analysis).append(": ").append(text);
}

}  // namespace

void TruncateMessage(std::string& message) {
  if (static_cast<int>(message.size()) <= kMessageLength) return;
  std::size_t cut = static_cast<std::size_t>(kMessageLength) - 3;
  while (cut > 0 && (static_cast<unsigned char>(message[cut]) & 0xC0) == 0x80) --cut;
  message.resize(cut);
  message += "...";
}

void ResultBlock::Allocate(const SweepPlan& plan) {
  const auto capacity = static_cast<std::size_t>(plan.chunk_runs());
  design_index.assign(capacity, 0);
  run_id.assign(capacity, 0);
  status.assign(capacity, 0);
  message.assign(capacity, std::string());
  design.assign(static_cast<std::size_t>(plan.design().column_count()), std::vector<double>(capacity));
  results.clear();
  for (const auto& column : plan.schema().columns) {
    results.emplace_back(capacity * static_cast<std::size_t>(column.doubles_per_run()));
  }
  chunk_count = 0;
  runs_failed = 0;
}

void ResultBlock::Reset(const SweepPlan& plan, std::int64_t index) {
  block_index = index;
  first_row = index * plan.chunk_runs();
  rows = static_cast<int>(std::min<std::int64_t>(plan.chunk_runs(), plan.run_count() - first_row));
  GESWEEP_DEMAND(rows >= 1 && static_cast<std::size_t>(rows) <= design_index.size());
  for (int r = 0; r < rows; ++r) {
    design_index[static_cast<std::size_t>(r)] = plan.first_run() + first_row + r;
    status[static_cast<std::size_t>(r)] = static_cast<std::int8_t>(RunStatus::kPending);
    message[static_cast<std::size_t>(r)].clear();
  }
  for (auto& column : results)
    std::fill(column.begin(), column.end(), std::numeric_limits<double>::quiet_NaN());
  chunk_count = 0;
  runs_failed = 0;
}

RunWorkspace::RunWorkspace(const SweepPlan& plan)
    : parameters(plan.base_parameters()),
      design_row(static_cast<std::size_t>(plan.design().column_count())) {}

const LongitudinalModel& RunWorkspace::Model(const SweepPlan& plan) {
  StartGroup();
  return GroupModel(plan, parameters);
}

void RunWorkspace::StartGroup() {
  ++group_;
  std::erase_if(models_, [&](const CachedModel& cached) { return cached.group < group_ - 1; });
}

const LongitudinalModel& RunWorkspace::GroupModel(const SweepPlan& plan,
                                                  const RunParameters& run_parameters) {
  const auto& ids = plan.model_parameters();
  auto same = [&](const CachedModel& cached) {
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (cached.key[i] != run_parameters[static_cast<std::size_t>(ids[i])]) return false;
    }
    return true;
  };
  // The last model built or used first: consecutive runs mostly share theirs.
  for (auto cached = models_.rbegin(); cached != models_.rend(); ++cached) {
    if (!same(*cached)) continue;
    cached->group = group_;
    return *cached->model;
  }
  CachedModel built;
  built.key.resize(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i)
    built.key[i] = run_parameters[static_cast<std::size_t>(ids[i])];
  built.model =
      std::make_unique<const LongitudinalModel>(*plan.study().aircraft, OptionsFrom(run_parameters));
  built.group = group_;
  models_.push_back(std::move(built));
  return *models_.back().model;
}

namespace {

// Sets run `row` of `block` up for design run `design_index`: `design_row` and `parameters` from the
// design (or from `design_values` when given), its design values, index and id; its message cleared.
void PrepareRun(const SweepPlan& plan, std::int64_t design_index, RunParameters& parameters,
                std::vector<double>& design_row, ResultBlock& block, int row,
                std::span<const double> design_values) {
  const auto r = static_cast<std::size_t>(row);
  const Design& design = plan.design();
  if (design_values.empty()) {
    design.Row(design_index, design_row.data());
  } else {
    GESWEEP_DEMAND(design_values.size() == design_row.size());
    std::copy(design_values.begin(), design_values.end(), design_row.begin());
  }
  parameters = plan.base_parameters();
  for (int c = 0; c < design.column_count(); ++c) {
    const double value = design_row[static_cast<std::size_t>(c)];
    parameters[static_cast<std::size_t>(design.spec().parameters[static_cast<std::size_t>(c)].id)] = value;
    block.design[static_cast<std::size_t>(c)][r] = value;
  }
  block.design_index[r] = design_index;
  block.run_id[r] = plan.RunId(design_row.data());
  block.message[r].clear();
}

// The run's model, or null with the run failed ("model: ...") when it cannot be built; null too when
// the study needs none (then `*failed` stays false).
template <class Build>
const LongitudinalModel* ModelOrFail(const SweepPlan& plan, ResultBlock& block, int row, bool* failed,
                                     const Build& build) {
  *failed = false;
  if (!plan.study().needs_model()) return nullptr;
  const auto r = static_cast<std::size_t>(row);
  try {
    return &build();
  } catch (const std::exception& e) {
    AppendMessage(block.message[r], "model", e.what());
    TruncateMessage(block.message[r]);
    block.status[r] = static_cast<std::int8_t>(RunStatus::kFailed);
    *failed = true;
    return nullptr;
  }
}

// The outcome of an analysis that threw `error`: a failed run whose message says what.
AnalysisOutcome OutcomeOfError(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    return AnalysisOutcome::Failed(std::string("exception: ") + e.what());
  } catch (...) {
    return AnalysisOutcome::Failed("unknown exception");
  }
}

// Adds an analysis' outcome to run `row`'s message and `ok`; false when it was cancelled: the run then
// stays pending ("cancelled") and no further analysis runs it.
bool TakeOutcome(const AnalysisOutcome& outcome, std::string_view analysis, ResultBlock& block, int row,
                 bool& ok) {
  const auto r = static_cast<std::size_t>(row);
  if (outcome.cancelled) {  // not a result: the run stays pending
    block.message[r] = "cancelled";
    block.status[r] = static_cast<std::int8_t>(RunStatus::kPending);
    return false;
  }
  ok = ok && outcome.ok;
  AppendMessage(block.message[r], analysis, outcome.message);
  return true;
}

// Run `row`'s status once every analysis has run it.
void FinishRun(ResultBlock& block, int row, bool ok) {
  const auto r = static_cast<std::size_t>(row);
  TruncateMessage(block.message[r]);
  block.status[r] = static_cast<std::int8_t>(ok ? RunStatus::kOk : RunStatus::kFailed);
}

}  // namespace

void ExecuteRun(const SweepPlan& plan, std::int64_t design_index, RunWorkspace& workspace, ResultBlock& block,
                int row, const std::atomic<bool>* cancel, std::span<const double> noise_point,
                std::span<const double> design_values) {
  PrepareRun(plan, design_index, workspace.parameters, workspace.design_row, block, row, design_values);
  bool failed = false;
  const LongitudinalModel* model = ModelOrFail(
      plan, block, row, &failed, [&]() -> const LongitudinalModel& { return workspace.Model(plan); });
  if (failed) return;
  // The run's global index in the design: its turbulence is RunNoise(seed, design_index).
  const RunContext context{workspace.parameters, model, cancel, static_cast<std::uint64_t>(design_index),
                           noise_point};
  OutputRow output(&block.results, &plan.schema(), row);
  bool ok = true;
  for (const auto& analysis : plan.study().analyses) {
    AnalysisOutcome outcome;
    try {
      outcome = analysis->Run(context, output);
    } catch (...) {
      outcome = OutcomeOfError(std::current_exception());
    }
    if (!TakeOutcome(outcome, analysis->name(), block, row, ok)) return;
  }
  FinishRun(block, row, ok);
}

void ExecuteRuns(const SweepPlan& plan, RunWorkspace& workspace, ResultBlock& block, int first_row, int count,
                 int lanes, const std::atomic<bool>* cancel,
                 std::span<const std::span<const double>> noise_points,
                 std::span<const std::span<const double>> design_values) {
  GESWEEP_DEMAND(std::ranges::find(kLaneWidths, lanes) != std::end(kLaneWidths));
  GESWEEP_DEMAND(count >= 0 && first_row >= 0 && first_row + count <= block.rows);
  GESWEEP_DEMAND(noise_points.empty() || noise_points.size() == static_cast<std::size_t>(count));
  GESWEEP_DEMAND(design_values.empty() || design_values.size() == static_cast<std::size_t>(count));
  workspace.StartGroup();
  if (workspace.group_parameters.size() < static_cast<std::size_t>(count)) {
    workspace.group_parameters.resize(static_cast<std::size_t>(count));
    workspace.group_rows.resize(static_cast<std::size_t>(count), workspace.design_row);
  }
  std::vector<RunContext> contexts;
  std::vector<OutputRow> outputs;
  std::vector<char> live, ok;  // a run every analysis so far ran to an end; and none failed it
  contexts.reserve(static_cast<std::size_t>(count));
  outputs.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    const int row = first_row + i;
    const auto k = static_cast<std::size_t>(i);
    const std::int64_t design_index = block.design_index[static_cast<std::size_t>(row)];
    RunParameters& parameters = workspace.group_parameters[k];
    PrepareRun(plan, design_index, parameters, workspace.group_rows[k], block, row,
               design_values.empty() ? std::span<const double>() : design_values[k]);
    bool failed = false;
    const LongitudinalModel* model =
        ModelOrFail(plan, block, row, &failed,
                    [&]() -> const LongitudinalModel& { return workspace.GroupModel(plan, parameters); });
    contexts.push_back(RunContext{parameters, model, cancel, static_cast<std::uint64_t>(design_index),
                                  noise_points.empty() ? std::span<const double>() : noise_points[k]});
    outputs.emplace_back(&block.results, &plan.schema(), row);
    live.push_back(failed ? 0 : 1);
    ok.push_back(1);
  }
  std::vector<LaneRun> runs;
  std::vector<int> run_of;  // runs[j] is run run_of[j] of the group
  for (const auto& analysis : plan.study().analyses) {
    runs.clear();
    run_of.clear();
    for (int i = 0; i < count; ++i) {
      if (!live[static_cast<std::size_t>(i)]) continue;
      runs.push_back({&contexts[static_cast<std::size_t>(i)], &outputs[static_cast<std::size_t>(i)], {}, {}});
      run_of.push_back(i);
    }
    analysis->RunLanes(runs, lanes);
    for (std::size_t j = 0; j < runs.size(); ++j) {
      const auto k = static_cast<std::size_t>(run_of[j]);
      const AnalysisOutcome outcome = runs[j].error ? OutcomeOfError(runs[j].error) : runs[j].outcome;
      bool run_ok = ok[k] != 0;
      live[k] = TakeOutcome(outcome, analysis->name(), block, first_row + run_of[j], run_ok) ? 1 : 0;
      ok[k] = run_ok ? 1 : 0;
    }
  }
  for (int i = 0; i < count; ++i) {
    if (live[static_cast<std::size_t>(i)])
      FinishRun(block, first_row + i, ok[static_cast<std::size_t>(i)] != 0);
  }
}

int DefaultLanes() {
  static const int lanes = LanesIsaSupported(LanesIsa::kAvx512) ? 8
                           : LanesIsaSupported(LanesIsa::kAvx2) ? 4
                                                                : 1;
  return lanes;
}

bool RunsInLanes(const SweepPlan& plan, int lanes) {
  if (lanes <= 1) return false;
  return std::ranges::any_of(plan.study().analyses,
                             [](const auto& analysis) { return analysis->takes_lanes(); });
}

namespace {

// Runs per lane in a group of ExecuteRuns: a lane whose run ended takes the group's next, so the
// lanes idle only at a group's end; 16 runs per lane keep that tail short and a batch of 2048
// open-loop runs in 16 or more groups for the threads to share.
constexpr int kGroupRunsPerLane = 16;

// Counts the computed runs [begin, end) of a batch into `counters` (a pending run, which a
// cancellation stopped, is not counted); returns the failed ones.
int CountRuns(const ResultBlock& block, int begin, int end, SweepProgress& counters) {
  int failed = 0, done = 0;
  for (int row = begin; row != end; ++row) {
    const auto status = block.status[static_cast<std::size_t>(row)];
    if (status == static_cast<std::int8_t>(RunStatus::kPending)) continue;
    failed += status == static_cast<std::int8_t>(RunStatus::kFailed);
    ++done;
  }
  counters.runs_done.fetch_add(done, std::memory_order_relaxed);
  counters.runs_failed.fetch_add(failed, std::memory_order_relaxed);
  return failed;
}

// Computes the runs of a batch in parallel (each thread in its own workspace), one at a time or in
// groups flown in lanes (RunsInLanes), counting them into `counters` and the batch's runs_failed; a
// cancellation leaves the rest of the batch pending.
void ComputeBatch(const SweepPlan& plan, ResultBlock& block,
                  tbb::enumerable_thread_specific<RunWorkspace>& workspaces, const RunnerOptions& options,
                  SweepProgress& counters) {
  const bool in_lanes = RunsInLanes(plan, options.lanes);
  const int group = in_lanes ? kGroupRunsPerLane * options.lanes : 1;
  auto cancelled = [&] { return options.cancel != nullptr && options.cancel->load(); };
  std::atomic<int> failed{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, block.rows, group), [&](const tbb::blocked_range<int>& range) {
    RunWorkspace& workspace = workspaces.local();
    for (int row = range.begin(); row < range.end() && !cancelled(); row += group) {
      const int count = std::min(group, range.end() - row);
      if (in_lanes) {
        ExecuteRuns(plan, workspace, block, row, count, options.lanes, options.cancel);
      } else {
        ExecuteRun(plan, block.design_index[static_cast<std::size_t>(row)], workspace, block, row,
                   options.cancel);
      }
      failed.fetch_add(CountRuns(block, row, row + count, counters), std::memory_order_relaxed);
    }
  });
  block.runs_failed = failed.load();
}

// Whether a run of the batch is still pending (a cancellation stopped it).
bool Unfinished(const ResultBlock& block) {
  const auto begin = block.status.begin();
  return std::find(begin, begin + block.rows, static_cast<std::int8_t>(RunStatus::kPending)) !=
         begin + block.rows;
}

/// One sweep's pipeline: batches from the source, computed and encoded by the workers, written in
/// the order they finish by a writer thread. Every batch in flight, queued or being written holds one
/// of the pool's buffers; a free one waits in free_blocks_.
class SweepPipeline {
 public:
  SweepPipeline(const SweepPlan& plan, BatchSource& source, ResultSink& sink, const RunnerOptions& options,
                SweepProgress& counters, int pool_size, int queue_capacity)
      : plan_(plan),
        source_(source),
        sink_(sink),
        options_(options),
        counters_(counters),
        pool_(static_cast<std::size_t>(pool_size)),
        workspaces_([&plan] { return RunWorkspace(plan); }) {
    for (auto& block : pool_) {
      block.Allocate(plan);
      free_blocks_.push(&block);
    }
    write_queue_.set_capacity(queue_capacity);
  }

  /// The writer thread: writes the queued batches until EndWrites, each buffer then freed; after a
  /// sink error it writes no more (the error kept, the pipeline stopped) but still frees them.
  void WriteQueued() {
    for (;;) {
      ResultBlock* block = nullptr;
      write_queue_.pop(block);
      if (block == nullptr) break;
      if (!writer_error_) {
        try {
          sink_.Write(*block);
          counters_.runs_written.fetch_add(block->rows, std::memory_order_relaxed);
        } catch (...) {
          writer_error_ = std::current_exception();
          stop_.store(true);
        }
      }
      free_blocks_.push(block);
    }
  }
  /// Tells the writer thread that no more batches come.
  void EndWrites() { write_queue_.push(nullptr); }

  /// The three stages on `threads` threads with `tokens` batches in flight, until the source is
  /// exhausted, a cancellation or a writer error.
  void Run(int threads, int tokens) {
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_pipeline(
          static_cast<std::size_t>(tokens),
          tbb::make_filter<void, ResultBlock*>(
              tbb::filter_mode::serial_in_order,
              [&](tbb::flow_control& control) { return NextBatch(control); }) &
              tbb::make_filter<ResultBlock*, ResultBlock*>(
                  tbb::filter_mode::parallel, [&](ResultBlock* block) { return ComputeAndEncode(block); }) &
              tbb::make_filter<ResultBlock*, void>(tbb::filter_mode::serial_out_of_order,
                                                   [&](ResultBlock* block) { QueueWrite(block); }));
    });
  }

  /// The error the sink threw, if any.
  std::exception_ptr writer_error() const { return writer_error_; }

  /// The runs' counts, and whether the sweep stopped short of the source's end (cancelled).
  SweepOutcome Outcome() const {
    SweepOutcome outcome;
    outcome.runs_failed = counters_.runs_failed.load();
    outcome.runs_ok = counters_.runs_done.load() - outcome.runs_failed;
    outcome.runs_skipped = counters_.runs_skipped.load();
    outcome.cancelled = !exhausted_ || dropped_.load() > 0;
    return outcome;
  }

 private:
  /// Stage 1 (serial, in order): the source's next batch in a free buffer; none (the pipeline stops)
  /// after a cancellation or a writer error, or when the source is exhausted.
  ResultBlock* NextBatch(tbb::flow_control& control) {
    const bool cancelled = options_.cancel != nullptr && options_.cancel->load();
    if (cancelled || stop_.load()) {
      control.stop();
      return nullptr;
    }
    const std::int64_t index = source_.Next();
    if (index < 0) {
      exhausted_ = true;
      control.stop();
      return nullptr;
    }
    ResultBlock* block = nullptr;
    free_blocks_.pop(block);
    block->Reset(plan_, index);
    return block;
  }

  /// Stage 2 (parallel): the batch's runs; the worker that computed the batch encodes it (filters its
  /// chunks). A batch a cancellation left unfinished is not encoded (nor written, in stage 3).
  ResultBlock* ComputeAndEncode(ResultBlock* block) {
    ComputeBatch(plan_, *block, workspaces_, options_, counters_);
    if (Unfinished(*block)) return block;
    sink_.Encode(*block);
    return block;
  }

  /// Stage 3 (serial, out of order): the batch to the writer thread; one a cancellation left
  /// unfinished is not written (its runs stay pending), its buffer freed.
  void QueueWrite(ResultBlock* block) {
    if (Unfinished(*block)) {
      dropped_.fetch_add(1);
      free_blocks_.push(block);
      return;
    }
    write_queue_.push(block);
  }

  const SweepPlan& plan_;
  BatchSource& source_;
  ResultSink& sink_;
  const RunnerOptions& options_;
  SweepProgress& counters_;
  std::vector<ResultBlock> pool_;
  tbb::concurrent_bounded_queue<ResultBlock*> free_blocks_, write_queue_;
  tbb::enumerable_thread_specific<RunWorkspace> workspaces_;
  std::atomic<bool> stop_{false};
  std::exception_ptr writer_error_;
  bool exhausted_ = false;
  std::atomic<std::size_t> dropped_{0};
};

}  // namespace

SweepOutcome RunSweep(const SweepPlan& plan, BatchSource& source, ResultSink& sink,
                      const RunnerOptions& options, SweepProgress* progress) {
  SweepProgress local_progress;
  SweepProgress& counters = progress ? *progress : local_progress;
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  const int tokens = kTokensPerThread * threads;
  const int queue_capacity = std::max(1, options.queue_batches);

  SweepPipeline pipeline(plan, source, sink, options, counters, tokens + queue_capacity + 1, queue_capacity);
  std::thread writer([&] { pipeline.WriteQueued(); });
  std::exception_ptr worker_error;
  try {
    pipeline.Run(threads, tokens);
  } catch (...) {
    worker_error = std::current_exception();
  }
  pipeline.EndWrites();
  writer.join();
  if (pipeline.writer_error()) std::rethrow_exception(pipeline.writer_error());
  if (worker_error) std::rethrow_exception(worker_error);
  return pipeline.Outcome();
}

SweepOutcome RunSweep(const SweepPlan& plan, const std::vector<std::int64_t>& pending_blocks,
                      ResultSink& sink, const RunnerOptions& options, SweepProgress* progress) {
  ListBatchSource source(pending_blocks);
  return RunSweep(plan, source, sink, options, progress);
}

}  // namespace gesweep
