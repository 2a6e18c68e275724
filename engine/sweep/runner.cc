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
  const auto& ids = plan.model_parameters();
  bool same = model_.has_value() && model_key_.size() == ids.size();
  for (std::size_t i = 0; same && i < ids.size(); ++i) {
    same = model_key_[i] == parameters[static_cast<std::size_t>(ids[i])];
  }
  if (!same) {
    model_.reset();
    model_key_.resize(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) model_key_[i] = parameters[static_cast<std::size_t>(ids[i])];
    model_.emplace(*plan.study().aircraft, OptionsFrom(parameters));
  }
  return *model_;
}

void ExecuteRun(const SweepPlan& plan, std::int64_t design_index, RunWorkspace& workspace, ResultBlock& block,
                int row, const std::atomic<bool>* cancel, std::span<const double> noise_point,
                std::span<const double> design_values) {
  const auto r = static_cast<std::size_t>(row);
  const Design& design = plan.design();
  if (design_values.empty()) {
    design.Row(design_index, workspace.design_row.data());
  } else {
    GESWEEP_DEMAND(design_values.size() == workspace.design_row.size());
    std::copy(design_values.begin(), design_values.end(), workspace.design_row.begin());
  }
  workspace.parameters = plan.base_parameters();
  for (int c = 0; c < design.column_count(); ++c) {
    const double value = workspace.design_row[static_cast<std::size_t>(c)];
    workspace.parameters[static_cast<std::size_t>(design.spec().parameters[static_cast<std::size_t>(c)].id)] =
        value;
    block.design[static_cast<std::size_t>(c)][r] = value;
  }
  block.design_index[r] = design_index;
  block.run_id[r] = plan.RunId(workspace.design_row.data());
  std::string& message = block.message[r];
  message.clear();
  bool ok = true;

  const LongitudinalModel* model = nullptr;
  if (plan.study().needs_model()) {
    try {
      model = &workspace.Model(plan);
    } catch (const std::exception& e) {
      AppendMessage(message, "model", e.what());
      TruncateMessage(message);
      block.status[r] = static_cast<std::int8_t>(RunStatus::kFailed);
      return;
    }
  }
  // The run's global index in the design: its turbulence is RunNoise(seed, design_index).
  const RunContext context{workspace.parameters, model, cancel, static_cast<std::uint64_t>(design_index),
                           noise_point};
  OutputRow output(&block.results, &plan.schema(), row);
  for (const auto& analysis : plan.study().analyses) {
    AnalysisOutcome outcome;
    try {
      outcome = analysis->Run(context, output);
    } catch (const std::exception& e) {
      outcome = AnalysisOutcome::Failed(std::string("exception: ") + e.what());
    } catch (...) {
      outcome = AnalysisOutcome::Failed("unknown exception");
    }
    if (outcome.cancelled) {  // not a result: the run stays pending
      message = "cancelled";
      block.status[r] = static_cast<std::int8_t>(RunStatus::kPending);
      return;
    }
    ok = ok && outcome.ok;
    AppendMessage(message, analysis->name(), outcome.message);
  }
  TruncateMessage(message);
  block.status[r] = static_cast<std::int8_t>(ok ? RunStatus::kOk : RunStatus::kFailed);
}

namespace {

// Computes the runs of a batch in parallel (each thread in its own workspace), counting them into
// `counters` and the batch's runs_failed; a cancellation leaves the rest of the batch pending.
void ComputeBatch(const SweepPlan& plan, ResultBlock& block,
                  tbb::enumerable_thread_specific<RunWorkspace>& workspaces, const RunnerOptions& options,
                  SweepProgress& counters) {
  std::atomic<int> failed{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, block.rows, 1), [&](const tbb::blocked_range<int>& range) {
    RunWorkspace& workspace = workspaces.local();
    int range_failed = 0;
    for (int row = range.begin(); row != range.end(); ++row) {
      if (options.cancel != nullptr && options.cancel->load()) break;
      ExecuteRun(plan, block.design_index[static_cast<std::size_t>(row)], workspace, block, row,
                 options.cancel);
      const auto status = block.status[static_cast<std::size_t>(row)];
      if (status == static_cast<std::int8_t>(RunStatus::kPending)) continue;
      range_failed += status == static_cast<std::int8_t>(RunStatus::kFailed);
      counters.runs_done.fetch_add(1, std::memory_order_relaxed);
    }
    failed.fetch_add(range_failed, std::memory_order_relaxed);
    counters.runs_failed.fetch_add(range_failed, std::memory_order_relaxed);
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
