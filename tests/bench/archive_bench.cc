// The HDF5 write per 1000 runs through the archive writer (issue 9, 14; docs/performance.md): what
// a finished batch costs, split the way `gesweep run` splits it since issue 14 -- the worker that
// computed it encodes it (shuffle + deflate + Fletcher-32 per chunk, ArchiveWriter::Encode) and the
// writer thread stores the chunks (H5Dwrite_chunk, flush, statuses, flush) -- for the columns of a
// modes study and of a modes + open-loop summary study. The batches hold real results, computed once
// before the timing (compression depends on the values), and are written into a fresh archive
// under $TMPDIR (default /tmp), deleted afterwards.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/archive/archive_writer.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"

namespace gesweep {
namespace {

// Studies written inline so the run count is the benchmark's; the path resolves the aircraft.
constexpr const char* kStudyPath = GESWEEP_SOURCE_DIR "/studies/bench/archive_bench.toml";

// 64 × 256 = 16,384 runs of modes over height × speed (4 batches of 4096).
constexpr const char* kModesStudy = R"(format_version = 1
name = "bench_archive_modes"
aircraft = "../aircraft/ance.toml"
[analyses.modes]
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [25.0, 60.0, 64]
[[design.parameter]]
name = "height_m"
logspace = [0.79, 14.0, 256]
)";

// 16 × 128 = 2,048 runs of modes + 30 s open loop, summaries only.
constexpr const char* kSummaryStudy = R"(format_version = 1
name = "bench_archive_modes_open_loop"
aircraft = "../aircraft/ance.toml"
[analyses.modes]
[analyses.open_loop]
duration_s = 30.0
[parameters]
pulse_amplitude_deg = 5.0
pulse_duration_s = 0.2
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [30.0, 50.0, 16]
[[design.parameter]]
name = "height_m"
logspace = [1.0, 14.0, 128]
)";

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::filesystem::path ScratchArchive(const std::string& name) {
  const char* tmp = std::getenv("TMPDIR");
  return std::filesystem::path(tmp && *tmp ? tmp : "/tmp") /
         ("gesweep_bench_" + name + "_" + std::to_string(getpid()) + ".h5");
}

void RemoveArchive(const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::remove(path, ec);
  std::filesystem::remove(path.string() + ".lock", ec);
  std::filesystem::remove(path.string() + ".partial", ec);
}

// Every batch of the plan, computed.
std::vector<ResultBlock> ComputeBlocks(const SweepPlan& plan) {
  std::vector<ResultBlock> blocks(static_cast<std::size_t>(plan.block_count()));
  RunWorkspace workspace(plan);
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    ResultBlock& block = blocks[b];
    block.Allocate(plan);
    block.Reset(plan, static_cast<std::int64_t>(b));
    for (int row = 0; row < block.rows; ++row) {
      ExecuteRun(plan, block.design_index[static_cast<std::size_t>(row)], workspace, block, row);
    }
  }
  return blocks;
}

// Each iteration creates an archive (not timed), writes every batch and finishes it (timed), and
// deletes it (not timed).
void WriteArchive(benchmark::State& state, const char* study_text, const std::string& name) {
  SweepPlan plan(ParseStudy(study_text, kStudyPath), ShardSpec{});
  std::vector<ResultBlock> blocks = ComputeBlocks(plan);
  const std::filesystem::path path = ScratchArchive(name);
  std::uintmax_t bytes = 0;
  double cpu_s = 0, encode_s = 0, store_s = 0;
  for (auto _ : state) {
    RemoveArchive(path);
    auto writer =
        ArchiveWriter::Open(path, plan, RunProvenance{"bench", 1}, ArchiveOpenMode::kCreate, nullptr);
    const double cpu_start = ThreadCpuSeconds();
    const auto start = std::chrono::steady_clock::now();
    for (ResultBlock& block : blocks) {
      const double t0 = ThreadCpuSeconds();
      writer->Encode(block);
      const double t1 = ThreadCpuSeconds();
      writer->Write(block);
      encode_s += t1 - t0;
      store_s += ThreadCpuSeconds() - t1;
    }
    writer->Finish();
    const auto stop = std::chrono::steady_clock::now();
    cpu_s += ThreadCpuSeconds() - cpu_start;
    writer.reset();
    state.SetIterationTime(std::chrono::duration<double>(stop - start).count());
    bytes = std::filesystem::file_size(path);
  }
  RemoveArchive(path);
  const double thousands = static_cast<double>(plan.run_count()) / 1000.0;
  state.counters["runs"] = static_cast<double>(plan.run_count());
  state.counters["chunk_runs"] = plan.chunk_runs();
  state.counters["bytes_per_run"] = static_cast<double>(bytes) / static_cast<double>(plan.run_count());
  state.counters["raw_bytes_per_run"] = static_cast<double>(plan.storage().bytes_per_run);
  // Seconds per 1000 runs, wall clock (printed with an SI prefix).
  state.counters["time_per_1000_runs"] = benchmark::Counter(
      thousands, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  // CPU seconds of the writing thread per 1000 runs: what the writer takes from the workers when
  // the cores are busy, and what a loaded machine inflates less than the wall clock.
  state.counters["cpu_per_1000_runs"] = cpu_s / static_cast<double>(state.iterations()) / thousands;
  // Of it: the workers' share (filtering the chunks) and the writer thread's (storing them).
  state.counters["encode_cpu_per_1000_runs"] = encode_s / static_cast<double>(state.iterations()) / thousands;
  state.counters["store_cpu_per_1000_runs"] = store_s / static_cast<double>(state.iterations()) / thousands;
}

// The study with an [output] table inserted before its first analysis: compression level (-1: the
// study default) and batch size (0: the plan's choice).
std::string WithOutput(const char* study_text, int compression_level, int chunk_runs) {
  std::string text = study_text;
  std::string output = "[output]\n";
  if (compression_level >= 0) output += "compression_level = " + std::to_string(compression_level) + "\n";
  if (chunk_runs > 0) output += "chunk_runs = " + std::to_string(chunk_runs) + "\n";
  text.insert(text.find("[analyses."), output);
  return text;
}

// Argument: the deflate level (1 is the study default; 0 stores without shuffle and deflate).
void BM_ArchiveWrite_Modes(benchmark::State& state) {
  const int level = static_cast<int>(state.range(0));
  WriteArchive(state, WithOutput(kModesStudy, level, 0).c_str(), "modes");
}
BENCHMARK(BM_ArchiveWrite_Modes)
    ->ArgName("deflate")
    ->Arg(1)
    ->Arg(4)
    ->Arg(0)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// Argument: runs per batch and chunk (0: the plan's choice, 128 for this study).
void BM_ArchiveWrite_ModesOpenLoopSummary(benchmark::State& state) {
  const int chunk = static_cast<int>(state.range(0));
  WriteArchive(state, WithOutput(kSummaryStudy, -1, chunk).c_str(), "summary");
}
BENCHMARK(BM_ArchiveWrite_ModesOpenLoopSummary)
    ->ArgName("chunk_runs")
    ->Arg(0)
    ->Arg(1024)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gesweep

BENCHMARK_MAIN();
