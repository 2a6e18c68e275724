// gesweep run: runs a study file's sweep into an HDF5 archive (docs/sweep.md).
//   gesweep run STUDY -o ARCHIVE [--threads N] [--shard i/N] [--resume] [--force] [--dry-run]
// Exit codes: 0 every run ok, 3 some runs failed, 2 bad input, 1 an I/O error, 128+signal when
// stopped by SIGINT/SIGTERM (the archive is then closed cleanly and resumable).
#include <tbb/info.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "engine/archive/archive_writer.h"
#include "engine/archive/write_cost.h"
#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/failure_text.h"
#include "engine/cli/json_util.h"
#include "engine/cli/request_names.h"
#include "engine/cli/signals.h"
#include "engine/common/errors.h"
#include "engine/common/output_guard.h"
#include "engine/sweep/run_cost.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#ifdef GESWEEP_HAVE_MPI
#include "engine/mpi/mpi_runner.h"
#endif

namespace gesweep::cli {
namespace {

// Dry run: the wall time its measurement may take, whatever the study (docs/sweep.md, "Dry run").
constexpr double kDefaultDryRunBudget_s = 2.0;
constexpr double kMaximumDryRunBudget_s = 600.0;
// Progress: a live bar refreshes this often on a terminal; a log line this often otherwise.
constexpr double kBarInterval_s = 0.25;
constexpr double kLogInterval_s = 5.0;

struct RunFlags {
  std::string study;
  std::string output;
  std::optional<int> threads;  // none: every core
  std::string shard;
  bool resume = false;
  bool force = false;
  bool dry_run = false;
  double dry_run_budget_s = kDefaultDryRunBudget_s;
  bool quiet = false;
  bool mpi = false;
  int ranks_per_node = 0;
  int lanes = DefaultLanes();
  std::string merge = "virtual";
  TextOrJson format = TextOrJson::kText;
  DescribedFlags described{{{"quiet", "-q"}}};

  /// The settings whose flag is their key's name (DescribedFlags, added by CommandWith); the study,
  /// the output, the threads (absent: every core), the shard, the format and the merge (MergeKind has
  /// no names table) are added by hand.
  template <class V>
  void Describe(V& v) {
    v(Field("resume", &resume).Doc("Continue an existing archive: skip complete runs, run the rest"));
    v(Field("force", &force).Doc("Replace an existing archive"));
    v(Field("dry_run", &dry_run)
          .Doc("Print the run count, storage and time estimates (measured on sample runs within "
               "--dry-run-budget-s); run nothing"));
    v(Field("dry_run_budget_s", &dry_run_budget_s)
          .Unit("s")
          .Limit("dry_run_budget_s")
          .Doc("Wall time the dry run's measurement may take, s (at most 600)"));
    v(Field("lanes", &lanes)
          .Limit("lanes")
          .Doc("Runs computed at once in SIMD lanes by the analyses that take them (open_loop with RK4 in "
               "still air, landing in turbulence with RK4): 1, 2, 4 or 8; 1 is one at a time. The archive "
               "is the same bit for bit whatever it is"));
    v(Field("quiet", &quiet).Doc("No progress output"));
    v(Field("mpi", &mpi).Doc("Spread the runs over MPI ranks: mpirun -n R gesweep run ... --mpi"));
    v(Field("ranks_per_node", &ranks_per_node)
          .Limit("ranks_per_node")
          .Doc("With --mpi: ranks per node, one shard writer each (0: $GESWEEP_RANKS_PER_NODE, else the "
               "ranks sharing a machine)"));
    v(Field("format", &format).Doc("Dry-run output: text for a person, JSON for a program"));
  }
};

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  std::ostringstream out;
  if (seconds < 1) {
    // Three significant digits, so that a sweep of milliseconds reads as one ("0.0234 s"): the dry
    // run's estimate is compared with this line (scripts/lib/dry_run_accuracy.py).
    const int decimals =
        seconds > 0 ? std::clamp(2 - static_cast<int>(std::floor(std::log10(seconds))), 2, 6) : 2;
    out << std::fixed << std::setprecision(decimals) << seconds << " s";
    return out.str();
  }
  if (seconds < 60) {
    out << std::fixed << std::setprecision(seconds < 10 ? 1 : 0) << seconds << " s";
    return out.str();
  }
  const auto total = static_cast<long long>(std::llround(seconds));
  if (total >= 86400) out << total / 86400 << "d ";
  const long long h = total / 3600 % 24, m = total / 60 % 60, s = total % 60;
  if (total >= 3600) {
    out << h << ":" << std::setw(2) << std::setfill('0') << m << ":" << std::setw(2) << s;
  } else {
    out << m << ":" << std::setw(2) << std::setfill('0') << s;
  }
  return out.str();
}

// A short time to 0.1 ms: the dry run's per-sweep parts.
std::string Milliseconds(double seconds) {
  if (seconds >= 1) return FormatDuration(seconds);
  return ShortNumber(std::round(seconds * 1e4) / 10) + " ms";
}

std::string CommandLine(const RunFlags& flags) {
  std::string line = "gesweep run " + flags.study + " -o " + flags.output;
  if (flags.threads) line += " --threads " + std::to_string(*flags.threads);
  if (flags.lanes != DefaultLanes()) line += " --lanes " + std::to_string(flags.lanes);
  if (!flags.shard.empty()) line += " --shard " + flags.shard;
  if (flags.resume) line += " --resume";
  if (flags.force) line += " --force";
  return line;
}

// Prints progress on stderr until stopped: a live bar on a terminal, a line every few seconds
// otherwise (logs, batch jobs).
class ProgressPrinter {
 public:
  ProgressPrinter(const SweepProgress& progress, bool enabled)
      : progress_(progress), terminal_(isatty(STDERR_FILENO) != 0), enabled_(enabled) {
    if (enabled_) thread_ = std::thread([this] { Loop(); });
  }
  ~ProgressPrinter() { Stop(); }
  void Stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  void Loop() {
    const auto start = std::chrono::steady_clock::now();
    const double interval = terminal_ ? kBarInterval_s : kLogInterval_s;
    std::unique_lock<std::mutex> lock(mutex_);
    bool printed = false;
    while (!wake_.wait_for(lock, std::chrono::duration<double>(interval), [this] { return stopping_; })) {
      Print(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      printed = true;
    }
    if (printed) {
      Print(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      if (terminal_) std::cerr << "\n";
    }
  }

  void Print(double elapsed_s) {
    const std::int64_t done = progress_.runs_done.load();
    const std::int64_t total = progress_.runs_to_do;
    const std::int64_t failed = progress_.runs_failed.load();
    const double rate = elapsed_s > 0 ? done / elapsed_s : 0;
    const double eta = rate > 0 ? (total - done) / rate : NAN;
    const double fraction = total > 0 ? static_cast<double>(done) / total : 1.0;
    std::ostringstream line;
    if (terminal_) {
      constexpr int kWidth = 30;
      const int filled = static_cast<int>(fraction * kWidth);
      line << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
           << std::string(static_cast<std::size_t>(kWidth - filled), ' ') << "] ";
    } else {
      line << "gesweep: ";
    }
    line << done << "/" << total << " runs (" << std::fixed << std::setprecision(1) << 100.0 * fraction
         << "%), " << std::setprecision(rate < 100 ? 1 : 0) << rate << " runs/s, ETA " << FormatDuration(eta);
    if (failed) line << ", " << failed << " failed";
    std::cerr << line.str() << (terminal_ ? "   " : "\n") << std::flush;
  }

  const SweepProgress& progress_;
  bool terminal_;
  bool enabled_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
};

// What the dry run measured, and the sweep time it gives (docs/sweep.md, "Dry run").
struct DryRunEstimate {
  RunCostEstimate cost;
  WriteCostEstimate write;
  double pipeline_s = 0;        // the pipeline's start and end
  bool fixed_measured = false;  // the per-sweep parts (archive set-up, pipeline, close) were timed
  double fixed_s = 0;           // their sum, 0 when not measured
  double estimate_s = 0;        // the sweep's time, and its 95 % interval
  double low_s = 0;
  double high_s = 0;
};

// Times sample runs and one real batch written to a scratch archive. Empty when a signal stopped it;
// `exit_code` is then the signal's.
std::optional<DryRunEstimate> EstimateSweep(SweepPlan& plan, int threads, const RunFlags& flags,
                                            int& exit_code) {
  DryRunEstimate e;
  {
    const SignalCancellation signals;
    // Most of the budget to the runs, the rest to one real batch written to a scratch archive.
    RunCostOptions options;
    options.threads = threads;
    options.budget_s = 0.75 * flags.dry_run_budget_s;
    options.lanes = flags.lanes;
    e.cost = EstimateRunCost(plan, options, signals.flag());
    if (!e.cost.stopped && !e.cost.lower_bound) {
      // What the sweep costs whatever its size: the pipeline's start and end (the process's first
      // use of TBB, as in the sweep), then the archive's set-up and close, timed on the scratch archive.
      e.pipeline_s = MeasurePipelineStart(plan, threads);
      try {
        e.write = MeasureWriteCost(plan, e.cost.seconds_per_run, 0.15 * flags.dry_run_budget_s,
                                   0.1 * flags.dry_run_budget_s);
      } catch (const ArchiveError&) {
        e.write = WriteCostEstimate{};  // no scratch space: the estimate leaves the writer out, and says so
      }
      e.fixed_measured = e.write.archive_measured;
    }
    if (e.cost.stopped || signals.cancelled()) {
      std::cerr << "gesweep: dry run stopped by signal " << signals.signal() << "\n";
      exit_code = signals.exit_code();
      return std::nullopt;
    }
  }
  e.fixed_s = e.fixed_measured ? e.write.open_seconds + e.pipeline_s + e.write.close_seconds : 0.0;
  const int cores = std::max(1, tbb::info::default_concurrency());
  // The workers run and encode; the writer thread stores.
  auto sweep_seconds = [&](double compute_s, double store_s) {
    const SweepTimeParts parts{compute_s, e.write.encode_seconds_per_run, store_s, e.fixed_s};
    return SweepSeconds(parts, plan.run_count(), plan.chunk_runs(), threads, cores);
  };
  e.estimate_s = sweep_seconds(e.cost.seconds_per_run, e.write.seconds_per_run);
  e.low_s = sweep_seconds(e.cost.seconds_per_run_low, e.write.seconds_per_run_low);
  e.high_s = e.cost.lower_bound ? INFINITY
                                : sweep_seconds(e.cost.seconds_per_run_high, e.write.seconds_per_run_high);
  return e;
}

void PrintDryRunJson(const SweepPlan& plan, int threads, const RunFlags& flags, const DryRunEstimate& e) {
  const auto& storage = plan.storage();
  const Study& study = plan.study();
  const RunCostEstimate& cost = e.cost;
  const WriteCostEstimate& write = e.write;
  nlohmann::json out = {
      {"study", study.path},
      {"name", study.name},
      {"design_kind", std::string(ToString(study.design.kind))},
      {"design_runs", plan.design_runs()},
      {"shard", std::to_string(plan.shard().index) + "/" + std::to_string(plan.shard().count)},
      {"first_run", plan.first_run()},
      {"run_count", plan.run_count()},
      {"chunk_runs", plan.chunk_runs()},
      {"bytes_per_run", storage.bytes_per_run},
      {"series_bytes_per_run", storage.series_bytes_per_run},
      {"storage_bytes", storage.bytes_per_run * plan.run_count()},
      {"design_storage_bytes", storage.design_bytes},
      {"seconds_per_run", cost.seconds_per_run},
      {"seconds_per_run_interval", {cost.seconds_per_run_low, JsonNumber(cost.seconds_per_run_high)}},
      {"write_seconds_per_run",
       write.measured ? nlohmann::json(write.seconds_per_run) : nlohmann::json(nullptr)},
      {"encode_seconds_per_run",
       write.measured ? nlohmann::json(write.encode_seconds_per_run) : nlohmann::json(nullptr)},
      {"fixed_seconds", e.fixed_measured ? nlohmann::json(e.fixed_s) : nlohmann::json(nullptr)},
      {"fixed_parts_seconds", e.fixed_measured ? nlohmann::json{{"archive_open", write.open_seconds},
                                                                {"pipeline", e.pipeline_s},
                                                                {"archive_close", write.close_seconds}}
                                               : nlohmann::json(nullptr)},
      {"calibration_runs", cost.timed_runs},
      {"warmup_runs", cost.warmup_runs},
      {"measured_seconds", cost.measured_s},
      {"budget_seconds", flags.dry_run_budget_s},
      {"lower_bound", cost.lower_bound},
      {"threads", threads},
      {"estimated_seconds", e.estimate_s},
      {"estimated_seconds_interval", {e.low_s, JsonNumber(e.high_s)}}};
  std::cout << out.dump(2) << "\n";
}

// "about 2 min (1 min to 3 min, 95 %) on 2 threads (3.1 us per run on a thread, ...)".
void PrintDryRunTime(int threads, const RunFlags& flags, const DryRunEstimate& e) {
  const RunCostEstimate& cost = e.cost;
  const WriteCostEstimate& write = e.write;
  const double us = cost.seconds_per_run * 1e6;
  const std::string per_run = us < 1e3   ? ShortNumber(std::round(us * 100) / 100) + " us"
                              : us < 1e6 ? ShortNumber(std::round(us / 10) / 100) + " ms"
                                         : ShortNumber(std::round(us / 1e4) / 100) + " s";
  if (cost.lower_bound) {
    std::cout << "time         more than " << FormatDuration(e.estimate_s) << " on " << threads << " thread"
              << (threads > 1 ? "s" : "") << ": a sample run did not finish within the "
              << ShortNumber(flags.dry_run_budget_s) << " s budget (more than " << per_run
              << " per run); --dry-run-budget-s measures longer\n";
    return;
  }
  std::cout << "time         about " << FormatDuration(e.estimate_s) << " (" << FormatDuration(e.low_s)
            << " to " << FormatDuration(e.high_s) << ", 95 %) on " << threads << " thread"
            << (threads > 1 ? "s" : "") << " (" << per_run << " per run on a thread, from " << cost.timed_runs
            << " sample run" << (cost.timed_runs == 1 ? "" : "s") << " after " << cost.warmup_runs
            << " warm-up";
  if (write.measured) {
    std::cout << "; encoding " << ShortNumber(std::round(write.encode_seconds_per_run * 1e8) / 100)
              << " us and storing " << ShortNumber(std::round(write.seconds_per_run * 1e8) / 100)
              << " us per run";
  } else {
    std::cout << "; writing not measured";
  }
  if (e.fixed_measured) {
    std::cout << "; per sweep " << Milliseconds(e.fixed_s) << ": archive set-up "
              << Milliseconds(write.open_seconds) << ", pipeline " << Milliseconds(e.pipeline_s) << ", close "
              << Milliseconds(write.close_seconds);
  } else {
    std::cout << "; fixed per-sweep part not measured";
  }
  std::cout << ")\n";
}

void PrintDryRunText(const SweepPlan& plan, int threads, const RunFlags& flags, const DryRunEstimate& e) {
  const auto& storage = plan.storage();
  const Study& study = plan.study();
  std::cout << "study        " << study.name << " (" << study.path << ")\n";
  std::cout << "analyses    ";
  for (const auto& analysis : study.analyses) std::cout << " " << analysis->name();
  std::cout << "\n";
  std::cout << "design       " << ToString(study.design.kind) << ", " << plan.design_runs() << " runs";
  if (plan.shard().count > 1) {
    std::cout << "; shard " << plan.shard().index << "/" << plan.shard().count << " runs " << plan.first_run()
              << ".." << plan.first_run() + plan.run_count() - 1 << " (" << plan.run_count() << " runs)";
  }
  std::cout << "\n";
  std::cout << "storage      about "
            << FormatBytes(static_cast<double>(storage.bytes_per_run * plan.run_count()))
            << " before compression (" << FormatBytes(static_cast<double>(storage.bytes_per_run))
            << " per run" << (storage.series_bytes_per_run ? ", time series included" : "") << ")\n";
  PrintDryRunTime(threads, flags, e);
  std::cout << "batches      " << plan.block_count() << " of " << plan.chunk_runs() << " runs\n";
}

int DryRun(SweepPlan& plan, int threads, const RunFlags& flags) {
  int exit_code = 0;
  const std::optional<DryRunEstimate> estimate = EstimateSweep(plan, threads, flags, exit_code);
  if (!estimate) return exit_code;
  if (flags.format == TextOrJson::kJson) {
    PrintDryRunJson(plan, threads, flags, *estimate);
  } else {
    PrintDryRunText(plan, threads, flags, *estimate);
  }
  return 0;
}

// The archive path, checked against the study's input files before anything is written: an output
// never replaces an input (engine/common/output_guard.h).
void CheckArchivePath(const RunFlags& flags, const Study& study) {
  const std::filesystem::path output(flags.output);
  CheckOutputPath(output, OutputKind::kFile, study.inputs, "-o",
                  {flags.output + ".partial", flags.output + ".lock"});
}

// Space the archive's file system must have free before a sweep starts or resumes: HDF5 1.10 can
// leave a variable-length attribute it was rewriting damaged when a write fails for want of space
// (found resuming on a full disk: "len not positive after adjustment for EOA"), so a sweep does not
// start on a disk that cannot take a few batches. A disk that fills later stops the sweep cleanly.
constexpr std::uintmax_t kMinimumFreeBytes = 16u << 20;

void CheckFreeSpace(const RunFlags& flags, const SweepPlan& plan) {
  std::filesystem::path directory = std::filesystem::path(flags.output).parent_path();
  if (directory.empty()) directory = ".";
  // A directory that cannot be written at all (a read-only file system, a read-only directory) is
  // the writer's to refuse, with its reason: "not enough space" would send the person the wrong way.
  if (access(directory.c_str(), W_OK) != 0) return;
  std::error_code ec;
  const std::filesystem::space_info space = std::filesystem::space(directory, ec);
  if (ec) return;  // unknown (the writer reports a missing directory itself)
  const auto batch_bytes = static_cast<std::uintmax_t>(plan.storage().bytes_per_run) *
                           static_cast<std::uintmax_t>(plan.chunk_runs());
  const std::uintmax_t needed = std::max(kMinimumFreeBytes, 2 * batch_bytes);
  if (space.available >= needed) return;
  throw ArchiveError("not enough space for the archive " + flags.output + ": " +
                         FormatBytes(static_cast<double>(space.available)) +
                         " free on its file system, at least " + FormatBytes(static_cast<double>(needed)) +
                         " needed to start safely; free some space and rerun (nothing was written)",
                     "no space left on device");
}

// One line for an archive the sweep could not write (disk full, quota, I/O error): which archive,
// the cause, what is kept and how to go on.
std::string WriteFailure(const RunFlags& flags, const std::string& cause, std::int64_t runs_kept) {
  return "cannot write the archive " + flags.output + ": " + cause + "; the " + std::to_string(runs_kept) +
         " runs of complete batches are kept; free the space or fix the cause, then continue with gesweep "
         "run " +
         flags.study + " -o " + flags.output + " --resume";
}

// mpirun -n R gesweep run ... --mpi (docs/cluster.md, "MPI"): the same pipeline with MPI as its
// transport; one writer per node writes the node's shard, rank 0 merges them into -o. RunStudyMpi
// initialises and finalises MPI itself and prints nothing; rank 0 prints here.
#ifdef GESWEEP_HAVE_MPI
// The MPI sweep's last lines on rank 0's stderr, and every rank's exit code: 0, 3 when runs failed,
// the signal's when stopped.
int ReportMpiSweepEnd(const RunFlags& flags, const MpiSweepReport& report,
                      const SignalCancellation& signals) {
  const bool speaks = report.rank == 0;
  if (speaks && (!flags.quiet || report.runs_failed > 0 || report.cancelled)) {
    std::int64_t ran = 0;
    for (const std::int64_t r : report.runs_per_rank) ran += r;
    std::ostringstream line;
    line << "gesweep: " << ran << " runs in " << FormatDuration(report.seconds) << " (" << std::fixed
         << std::setprecision(1) << (report.seconds > 0 ? ran / report.seconds : 0.0) << " runs/s) on "
         << report.ranks << " ranks (runs per rank:";
    for (const std::int64_t r : report.runs_per_rank) line << " " << r;
    line << "); " << report.runs_ok << " ok, " << report.runs_failed << " failed, " << report.runs_pending
         << " pending in " << report.node_archives.size() << " node shard"
         << (report.node_archives.size() > 1 ? "s" : "");
    if (report.merged) {
      line << " -> " << flags.output << " ("
           << (report.merge.kind == MergeKind::kVirtual ? "virtual: keep the node shards beside it"
                                                        : "copied: self-contained")
           << ")";
    }
    std::cerr << line.str() << "\n";
  }
  if (report.cancelled) {
    if (speaks)
      std::cerr << "gesweep: stopped by signal " << signals.signal() << "; continue with --resume\n";
    return signals.exit_code();
  }
  if (report.runs_failed > 0) {
    if (speaks) {
      std::cerr << "gesweep: " << report.runs_failed
                << " runs failed; their status is 'failed' and runs/message says why\n";
    }
    return 3;
  }
  return 0;
}
#endif

int RunMpi(const RunFlags& flags, const SweepPlan& plan) {
#ifdef GESWEEP_HAVE_MPI
  if (flags.merge != "virtual" && flags.merge != "copy") {
    throw InputError("command line", "--merge", "'" + flags.merge + "'", "expected virtual or copy");
  }
  if (flags.ranks_per_node < 0) {
    throw InputError("command line", "--ranks-per-node", std::to_string(flags.ranks_per_node),
                     "expected a whole number >= 1 (0: the ranks that share a machine)");
  }
  const SignalCancellation signals;  // SIGINT/SIGTERM stop every rank between two steps
  MpiRunOptions options;
  options.output = flags.output;
  options.mode = flags.resume ? ArchiveOpenMode::kResume
                              : (flags.force ? ArchiveOpenMode::kForce : ArchiveOpenMode::kCreate);
  options.threads = flags.threads.value_or(0);
  options.command_line = CommandLine(flags) + " --mpi";
  options.cancel = signals.flag();
  options.ranks_per_node = flags.ranks_per_node;
  options.lanes = flags.lanes;
  options.describe_input_error = [](const InputError& e) { return std::string(ForCommandLine(e).what()); };
  options.merge = flags.merge == "copy" ? MergeKind::kCopy : MergeKind::kVirtual;
  MpiFinalizer finalize_after_printing;
  SweepProgress progress;
  std::unique_ptr<ProgressPrinter> printer;
  const int threads = flags.threads.value_or(tbb::info::default_concurrency());
  MpiSweepReport report;
  try {
    report = RunStudyMpi(plan, options, &progress, [&](const MpiSweepReport& started) {
      if (started.rank != 0 || flags.quiet) return;
      std::cerr << "gesweep: " << plan.study().name << ": " << plan.design_runs() << " runs";
      if (plan.shard().count > 1) std::cerr << ", shard " << plan.shard().index << "/" << plan.shard().count;
      std::cerr << ", " << started.ranks << " MPI rank" << (started.ranks > 1 ? "s" : "") << " x " << threads
                << " thread" << (threads > 1 ? "s" : "") << " on " << started.nodes << " node"
                << (started.nodes > 1 ? "s" : "") << " -> " << flags.output << " (node shards "
                << NodeArchivePath(flags.output, 0, started.nodes).filename().string()
                << (started.nodes > 1 ? " ..." : "") << ")\n";
      if (started.runs_complete_at_start > 0) {
        std::cerr << "gesweep: resuming: " << started.runs_complete_at_start << " runs already complete, "
                  << started.runs_to_do << " to run\n";
      }
      printer = std::make_unique<ProgressPrinter>(progress, started.runs_to_do > 0);
    });
  } catch (const std::exception& e) {
    if (printer) printer->Stop();
    std::cerr << "\ngesweep: error: " << e.what() << " (stopping every rank)\n";
    AbortMpi(1);
  }
  if (printer) printer->Stop();
  const bool speaks = report.rank == 0;
  if (report.error_code != 0) {
    if (speaks) {
      std::cerr << "gesweep: error: " << report.error;
      if (report.error_code == 1)
        std::cerr << " (the runs written so far are kept in the node shards; fix the cause and rerun with "
                     "--resume)";
      std::cerr << "\n";
    }
    return report.error_code;
  }
  return ReportMpiSweepEnd(flags, report, signals);
#else
  (void)plan;
  throw InputError("command line", "--mpi", "", "this gesweep was built without MPI (libopenmpi-dev)");
#endif
}

// The checks of the flags among themselves, before the study is read.
void CheckRunFlags(const RunFlags& flags) {
  if (flags.resume && flags.force) {
    throw InputError("command line", "--force", "", "cannot be combined with --resume (choose one)");
  }
  if (flags.threads && (*flags.threads < 1 || *flags.threads > 4096)) {
    throw InputError("command line", "--threads", std::to_string(*flags.threads),
                     "expected 1 to 4096 worker threads; leave --threads out to use every core");
  }
  if (std::ranges::find(kLaneWidths, flags.lanes) == std::end(kLaneWidths)) {
    throw InputError("command line", "--lanes", std::to_string(flags.lanes), "expected 1, 2, 4 or 8 lanes");
  }
  if (!(flags.dry_run_budget_s > 0.0) || flags.dry_run_budget_s > kMaximumDryRunBudget_s) {
    throw InputError("command line", "--dry-run-budget-s", ShortNumber(flags.dry_run_budget_s),
                     "expected a time in (0, " + ShortNumber(kMaximumDryRunBudget_s) + "] s");
  }
}

// The sweep's first lines on stderr: what runs where, and what a resume found.
void AnnounceSweep(const RunFlags& flags, const SweepPlan& plan, int threads, const ArchiveOpenReport& opened,
                   std::int64_t runs_to_do) {
  std::cerr << "gesweep: " << plan.study().name << ": " << plan.design_runs() << " runs";
  if (plan.shard().count > 1) {
    std::cerr << ", shard " << plan.shard().index << "/" << plan.shard().count << " = runs "
              << plan.first_run() << ".." << plan.first_run() + plan.run_count() - 1;
  }
  std::cerr << ", " << threads << " thread" << (threads > 1 ? "s" : "") << " -> " << flags.output << "\n";
  if (opened.kind != ArchiveOpenReport::Kind::kCreated) {
    std::cerr << "gesweep: resuming"
              << (opened.kind == ArchiveOpenReport::Kind::kResumedAfterCrash
                      ? " from a fresh copy of its complete batches (" + opened.note + ")"
                      : std::string())
              << ": " << opened.runs_complete << " runs already complete, " << runs_to_do << " to run\n";
  }
}

// The sweep's last lines on stderr, and the command's exit code: 0, 3 when runs failed, the signal's
// when stopped (docs/sweep.md).
int ReportSweepEnd(const RunFlags& flags, const ArchiveWriter& writer, bool cancelled,
                   const SignalCancellation& signals, std::int64_t ran, double elapsed) {
  if (!flags.quiet || writer.runs_failed() > 0 || cancelled) {
    std::cerr << "gesweep: " << ran << " runs in " << FormatDuration(elapsed) << " (" << std::fixed
              << std::setprecision(1) << (elapsed > 0 ? ran / elapsed : 0.0)
              << " runs/s); archive: " << writer.runs_ok() << " ok, " << writer.runs_failed() << " failed, "
              << writer.runs_pending() << " pending -> " << flags.output << "\n";
  }
  if (cancelled) {
    std::cerr << "gesweep: stopped by signal " << signals.signal() << "; continue with --resume\n";
    return signals.cancelled() ? signals.exit_code() : 1;
  }
  if (writer.runs_failed() > 0) {
    std::cerr << "gesweep: " << writer.runs_failed()
              << " runs failed; their status is 'failed' and runs/message says why\n";
    return 3;
  }
  return 0;
}

// The study to run: loaded, not a subset simulation, its archive path (when given) one it may write.
// Throws InputError.
Study LoadRunStudy(const RunFlags& flags) {
  Study study = LoadStudy(flags.study);
  if (study.subset_line != 0) {
    throw InputError(study.path, "subset", "",
                     "a study with a [subset] table is a subset simulation: run it with `gesweep risk " +
                         study.path + " -o ARCHIVE` (docs/dispersion.md)",
                     study.subset_line);
  }
  if (!flags.output.empty()) CheckArchivePath(flags, study);
  return study;
}

// Opens the archive (created, forced or resumed), what it holds into `opened`; nullptr, the error
// said on stderr, when it cannot be set up.
std::unique_ptr<ArchiveWriter> OpenRunArchive(const RunFlags& flags, SweepPlan& plan, int threads,
                                              ArchiveOpenReport& opened) {
  try {
    return ArchiveWriter::Open(flags.output, plan, RunProvenance{CommandLine(flags), threads},
                               flags.resume
                                   ? ArchiveOpenMode::kResume
                                   : (flags.force ? ArchiveOpenMode::kForce : ArchiveOpenMode::kCreate),
                               &opened);
  } catch (const ArchiveError& e) {
    std::cerr << "gesweep: error: cannot set up the archive " << EscapeForMessage(flags.output) << ": "
              << EscapeForMessage(e.cause()) << "\n";
    return nullptr;
  }
}

int Run(const RunFlags& flags) {
  CheckRunFlags(flags);
  ShardSpec shard;
  if (!flags.shard.empty()) shard = ParseShard(flags.shard, "--shard");
  SweepPlan plan(LoadRunStudy(flags), shard);
  const int threads = flags.threads.value_or(tbb::info::default_concurrency());
  if (flags.dry_run) return DryRun(plan, threads, flags);
  if (flags.output.empty())
    throw InputError("command line", "-o", "", "missing: the archive to write, e.g. -o results/out.h5");
  if (flags.mpi) return RunMpi(flags, plan);
  if (flags.ranks_per_node != 0 || flags.merge != "virtual") {
    throw InputError("command line", flags.ranks_per_node != 0 ? "--ranks-per-node" : "--merge", "",
                     "only with --mpi");
  }

  // From here on SIGINT/SIGTERM stop the sweep between two integration steps (exit 128 + signal);
  // what is complete stays in the archive for --resume.
  const SignalCancellation signals;
  ArchiveOpenReport opened;
  std::unique_ptr<ArchiveWriter> writer;
  try {
    CheckFreeSpace(flags, plan);
  } catch (const ArchiveError& e) {
    std::cerr << "gesweep: error: " << EscapeForMessage(e.what()) << "\n";
    return 1;
  }
  // The sweep's time ("N runs in T") runs from here, the archive's set-up, to its close: the
  // interval the dry run estimates (docs/sweep.md, "Dry run").
  const auto start = std::chrono::steady_clock::now();
  writer = OpenRunArchive(flags, plan, threads, opened);
  if (!writer) return 1;

  SweepProgress progress;
  progress.runs_skipped = opened.runs_complete;
  progress.runs_to_do = plan.run_count() - opened.runs_complete;
  if (!flags.quiet) AnnounceSweep(flags, plan, threads, opened, progress.runs_to_do);

  // A write or run failure: one line saying what is kept (exit 1).
  auto failed = [&](const std::string& cause) {
    std::cerr << "gesweep: error: "
              << EscapeForMessage(
                     WriteFailure(flags, cause, opened.runs_complete + progress.runs_written.load()))
              << "\n";
    return 1;
  };
  SweepOutcome outcome;
  {
    ProgressPrinter printer(progress, !flags.quiet && progress.runs_to_do > 0);
    RunnerOptions options;
    options.threads = threads;
    options.cancel = signals.flag();
    options.lanes = flags.lanes;
    try {
      outcome = RunSweep(plan, opened.pending_blocks, *writer, options, &progress);
    } catch (const ArchiveError& e) {
      printer.Stop();  // ends its line on a terminal, so the error is one line of its own
      return failed(e.cause());
    } catch (const std::exception& e) {
      printer.Stop();
      return failed(FailureInWords(e));  // never a library's own text (issue 26, item 6)
    }
  }
  try {
    writer->Finish();
  } catch (const ArchiveError& e) {
    return failed(e.cause());
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return ReportSweepEnd(flags, *writer, outcome.cancelled, signals, progress.runs_done.load(), elapsed);
}

void AddRunFlags(CLI::App& app, RunFlags& flags) {
  app.add_option("study", flags.study, "Study file (TOML), e.g. studies/stability_map.toml")->required();
  app.add_option("-o,--output", flags.output, "Archive to write (HDF5), e.g. results/stability_map.h5");
  app.add_option("--threads", flags.threads, "Worker threads, 1 to 4096 (default, when left out: all cores)")
      ->check(ExactIntegerValidator("--threads", "threads", std::numeric_limits<int>::max()));
  app.add_option("--shard", flags.shard,
                 "Run only shard i of N (i/N, 0 <= i < N): a contiguous block of the design");
  app.add_option("--merge", flags.merge,
                 "With --mpi: how the node shards become the archive: virtual (default; they stay beside it) "
                 "or copy (self-contained)");
}

const CommandRegistrar kRegistrar{CommandWith<RunFlags>(
    "run", "Run a study file's sweep into an HDF5 archive (exit 0 all ok, 3 some runs failed, 2 bad input)",
    AddRunFlags, Run)};

}  // namespace
}  // namespace gesweep::cli
