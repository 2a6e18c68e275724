// Sweep throughput through the runner API (issue 9; docs/performance.md, run by
// `./scripts/bench --sweep`): the runs/s of a study's whole sweep on N threads, compute-only (the
// runner with a sink that discards the batches) beside compute + write (the runner with the HDF5
// ArchiveWriter, exactly as `gesweep run` drives them, minus the progress printer), alternated
// repetition by repetition (and thread count by thread count) so that all see the same machine
// load; the CPU time of each sweep (user + system, all threads), so that a 2-thread sweep that does
// no more work per run than a 1-thread one can be told from a machine whose other load took the
// second core; and the process's peak resident memory (getrusage). Prints one JSON object on stdout.
//
//   gesweep_sweep_throughput STUDY [--threads N[,N...]] [--repetitions R] [--mode both|compute|write]
//                            [--archive PATH]
//
// The archive (default $TMPDIR/gesweep_throughput_<pid>.h5) is deleted after each repetition.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "engine/archive/archive_writer.h"
#include "engine/common/errors.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"

namespace gesweep {
namespace {

// Discards every batch, counting its runs by status: the compute-only sweep.
class DiscardingSink final : public ResultSink {
 public:
  void Write(const ResultBlock& block) override {
    for (int r = 0; r < block.rows; ++r) {
      const auto status = static_cast<RunStatus>(block.status[static_cast<std::size_t>(r)]);
      ok_ += status == RunStatus::kOk;
      failed_ += status == RunStatus::kFailed;
    }
  }
  std::int64_t ok() const { return ok_; }
  std::int64_t failed() const { return failed_; }

 private:
  std::int64_t ok_ = 0, failed_ = 0;
};

struct Options {
  std::string study;
  std::vector<int> threads = {1};
  int repetitions = 3;
  std::string mode = "both";
  std::filesystem::path archive;
};

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

void RemoveArchive(const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::remove(path, ec);
  std::filesystem::remove(path.string() + ".lock", ec);
  std::filesystem::remove(path.string() + ".partial", ec);
}

std::vector<std::int64_t> AllBlocks(const SweepPlan& plan) {
  std::vector<std::int64_t> blocks(static_cast<std::size_t>(plan.block_count()));
  std::iota(blocks.begin(), blocks.end(), std::int64_t{0});
  return blocks;
}

struct Timing {
  double seconds = 0;
  double cpu_seconds = 0;  ///< user + system time of the process during the sweep
  std::int64_t ok = 0, failed = 0;
  std::uintmax_t archive_bytes = 0;
};

double ProcessCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

Timing ComputeOnly(const SweepPlan& plan, int threads) {
  DiscardingSink sink;
  RunnerOptions options;
  options.threads = threads;
  const double cpu_start = ProcessCpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  RunSweep(plan, AllBlocks(plan), sink, options, nullptr);
  Timing t;
  t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  t.cpu_seconds = ProcessCpuSeconds() - cpu_start;
  t.ok = sink.ok();
  t.failed = sink.failed();
  return t;
}

// As `gesweep run`: open (create the skeleton), run, finish; timed from open to finish.
Timing ComputeAndWrite(SweepPlan& plan, int threads, const std::filesystem::path& path) {
  RemoveArchive(path);
  RunnerOptions options;
  options.threads = threads;
  const double cpu_start = ProcessCpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  ArchiveOpenReport opened;
  auto writer = ArchiveWriter::Open(path, plan, RunProvenance{"gesweep_sweep_throughput", threads},
                                    ArchiveOpenMode::kCreate, &opened);
  RunSweep(plan, opened.pending_blocks, *writer, options, nullptr);
  writer->Finish();
  Timing t;
  t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  t.cpu_seconds = ProcessCpuSeconds() - cpu_start;
  t.ok = writer->runs_ok();
  t.failed = writer->runs_failed();
  writer.reset();
  t.archive_bytes = std::filesystem::file_size(path);
  RemoveArchive(path);
  return t;
}

nlohmann::json Summary(const std::vector<Timing>& timings, std::int64_t runs) {
  std::vector<double> seconds, cpu_seconds;
  for (const Timing& t : timings) {
    seconds.push_back(t.seconds);
    cpu_seconds.push_back(t.cpu_seconds);
  }
  const double median = Median(seconds);
  nlohmann::json out = {{"seconds", seconds},
                        {"median_s", median},
                        {"runs_per_s", static_cast<double>(runs) / median},
                        {"cpu_seconds", cpu_seconds},
                        {"cpu_us_per_run", 1e6 * Median(cpu_seconds) / static_cast<double>(runs)},
                        {"runs_ok", timings.back().ok},
                        {"runs_failed", timings.back().failed}};
  if (timings.back().archive_bytes) out["archive_bytes"] = timings.back().archive_bytes;
  return out;
}

int Main(int argc, char** argv) {
  Options o;
  std::vector<std::string> args(argv + 1, argv + argc);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw InputError("command line", a, "", "expected a value");
      return args[++i];
    };
    if (a == "--threads") {
      o.threads.clear();
      std::stringstream list(value());
      for (std::string item; std::getline(list, item, ',');) o.threads.push_back(std::stoi(item));
    } else if (a == "--repetitions") {
      o.repetitions = std::stoi(value());
    } else if (a == "--mode") {
      o.mode = value();
    } else if (a == "--archive") {
      o.archive = value();
    } else if (!a.empty() && a[0] != '-' && o.study.empty()) {
      o.study = a;
    } else {
      throw InputError("command line", a, "",
                       "usage: gesweep_sweep_throughput STUDY [--threads N] "
                       "[--repetitions R] [--mode both|compute|write] [--archive PATH]");
    }
  }
  if (o.study.empty()) throw InputError("command line", "STUDY", "", "missing: a study file");
  if (o.repetitions < 1 || o.threads.empty() || *std::min_element(o.threads.begin(), o.threads.end()) < 1) {
    throw InputError("command line", "--threads/--repetitions", "", "expected whole numbers >= 1");
  }
  if (o.mode != "both" && o.mode != "compute" && o.mode != "write") {
    throw InputError("command line", "--mode", o.mode, "expected both, compute or write");
  }
  if (o.archive.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    o.archive = std::filesystem::path(tmp && *tmp ? tmp : "/tmp") /
                ("gesweep_throughput_" + std::to_string(getpid()) + ".h5");
  }

  SweepPlan plan(LoadStudy(o.study), ShardSpec{});
  const std::string load_before = LoadAverage();
  const std::size_t configurations = o.threads.size();
  std::vector<std::vector<Timing>> compute(configurations), write(configurations);
  for (int r = 0; r < o.repetitions; ++r) {
    for (std::size_t k = 0; k < configurations; ++k) {
      if (o.mode != "write") compute[k].push_back(ComputeOnly(plan, o.threads[k]));
      if (o.mode != "compute") write[k].push_back(ComputeAndWrite(plan, o.threads[k], o.archive));
    }
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  nlohmann::json results = nlohmann::json::array();
  for (std::size_t k = 0; k < configurations; ++k) {
    nlohmann::json result = {{"threads", o.threads[k]}};
    if (!compute[k].empty()) result["compute_only"] = Summary(compute[k], plan.run_count());
    if (!write[k].empty()) result["compute_write"] = Summary(write[k], plan.run_count());
    if (!compute[k].empty() && !write[k].empty()) {
      // The share of the compute-only throughput that writing costs, from the medians.
      const double c = result["compute_only"]["runs_per_s"], w = result["compute_write"]["runs_per_s"];
      result["write_cost_fraction"] = 1.0 - w / c;
    }
    results.push_back(result);
  }
  nlohmann::json out = {{"study", o.study},
                        {"name", plan.study().name},
                        {"runs", plan.run_count()},
                        {"chunk_runs", plan.chunk_runs()},
                        {"repetitions", o.repetitions},
                        {"raw_bytes_per_run", plan.storage().bytes_per_run},
                        {"peak_rss_kb", usage.ru_maxrss},
                        {"load_average_before", load_before},
                        {"load_average_after", LoadAverage()},
                        {"results", results}};
  std::cout << out.dump(2) << "\n";
  return 0;
}

}  // namespace
}  // namespace gesweep

int main(int argc, char** argv) {
  try {
    return gesweep::Main(argc, argv);
  } catch (const gesweep::InputError& e) {
    std::cerr << "gesweep_sweep_throughput: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "gesweep_sweep_throughput: error: " << e.what() << "\n";
    return 1;
  }
}
