#include "engine/archive/write_cost.h"

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "engine/archive/archive_writer.h"
#include "engine/sweep/run_cost.h"
#include "engine/sweep/runner.h"

namespace gesweep {
namespace {

using Clock = std::chrono::steady_clock;

// The scratch archive's timings of storing batches.
struct WriteTimes {
  double seconds = 0;
  double encode_seconds = 0;
  std::vector<double> per_run;  // each batch's seconds per run (storing)
};

// Each batch of the scratch archive once (each chunk is written exactly once), the same data
// `block`, until the last whole batch or `write_budget_s`; counts the runs in estimate.runs_written.
WriteTimes WriteBatches(ArchiveWriter& writer, const SweepPlan& plan, ResultBlock& block,
                        double write_budget_s, WriteCostEstimate& estimate) {
  WriteTimes times;
  ResultBlock encoded;
  const auto start = Clock::now();
  for (std::int64_t b = 0; b < plan.block_count(); ++b) {
    block.block_index = b;
    block.first_row = b * plan.chunk_runs();
    if (b > 0 && block.first_row + block.rows > plan.run_count()) break;  // a short last batch
    // As the sweep does it: a worker encodes the batch, the writer thread stores its chunks.
    encoded = block;
    const auto encode_start = Clock::now();
    writer.Encode(encoded);
    const auto write_start = Clock::now();
    times.encode_seconds += std::chrono::duration<double>(write_start - encode_start).count();
    writer.Write(encoded);
    const double batch_s = std::chrono::duration<double>(Clock::now() - write_start).count();
    times.seconds += batch_s;
    times.per_run.push_back(batch_s / block.rows);
    estimate.runs_written += block.rows;
    if (std::chrono::duration<double>(Clock::now() - start).count() > write_budget_s) break;
  }
  return times;
}

// The storing cost per run from the batches written, with a 95 % interval from their scatter when
// there are three or more.
void SetStoringCost(const WriteTimes& times, WriteCostEstimate& estimate) {
  if (estimate.runs_written > 0) {
    estimate.seconds_per_run = times.seconds / static_cast<double>(estimate.runs_written);
    estimate.encode_seconds_per_run = times.encode_seconds / static_cast<double>(estimate.runs_written);
    estimate.seconds_per_run_low = estimate.seconds_per_run_high = estimate.seconds_per_run;
    estimate.measured = true;
  }
  // On the batches' scatter.
  SetInterval95(times.per_run, estimate.seconds_per_run, estimate.seconds_per_run_low,
                estimate.seconds_per_run_high);
}

}  // namespace

WriteCostEstimate MeasureWriteCost(SweepPlan& plan, double seconds_per_run_compute, double compute_budget_s,
                                   double write_budget_s) {
  WriteCostEstimate estimate;
  const bool write_batch =
      plan.block_count() >= 1 && seconds_per_run_compute * plan.chunk_runs() <= compute_budget_s;
  ResultBlock block;
  if (write_batch) {
    block.Allocate(plan);
    block.Reset(plan, 0);
    RunWorkspace workspace(plan);
    for (int row = 0; row < block.rows; ++row) {
      ExecuteRun(plan, block.design_index[static_cast<std::size_t>(row)], workspace, block, row);
    }
  }
  std::string pattern = (std::filesystem::temp_directory_path() / "gesweep_write_cost.XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) return estimate;
  const std::filesystem::path directory(pattern);
  WriteTimes times;
  {
    std::unique_ptr<ArchiveWriter> writer;
    try {
      const auto open_start = Clock::now();
      writer = ArchiveWriter::Open(directory / "scratch.h5", plan,
                                   RunProvenance{"gesweep run, dry run: write cost", 1},
                                   ArchiveOpenMode::kCreate, nullptr);
      estimate.open_seconds = std::chrono::duration<double>(Clock::now() - open_start).count();
      if (write_batch) times = WriteBatches(*writer, plan, block, write_budget_s, estimate);
      const auto close_start = Clock::now();
      writer->Finish();
      estimate.close_seconds = std::chrono::duration<double>(Clock::now() - close_start).count();
      estimate.archive_measured = true;
    } catch (...) {
      writer.reset();
      std::error_code ec;
      std::filesystem::remove_all(directory, ec);
      throw;
    }
  }
  std::error_code ec;
  std::filesystem::remove_all(directory, ec);
  SetStoringCost(times, estimate);
  return estimate;
}

}  // namespace gesweep
