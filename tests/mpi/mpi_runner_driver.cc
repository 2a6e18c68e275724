// mpi_runner_driver: runs a study through RunStudyMpi (engine/mpi) without the CLI, so the MPI
// runner is tested end to end (tests/mpi/mpi_test.py) whether or not `gesweep run --mpi` is wired.
//   mpirun -n R mpi_runner_driver STUDY -o ARCHIVE [--threads N] [--shard i/N] [--force|--resume]
//                                 [--prefetch N] [--ranks-per-node N] [--copy] [--quiet]
// Exit codes as `gesweep run`: 0 all ok, 3 some runs failed, 2 bad input, 1 an I/O error.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <iostream>
#include <string>

#include "engine/common/errors.h"
#include "engine/mpi/mpi_runner.h"
#include "engine/sweep/study.h"

namespace {
std::atomic<bool> g_cancel{false};
std::atomic<int> g_signal{0};
extern "C" void OnSignal(int signal) {
  g_signal.store(signal);
  g_cancel.store(true);
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Runs a study through the MPI runner (test driver of engine/mpi)"};
  std::string study_path, output, shard;
  int threads = 0, prefetch = 0, ranks_per_node = 0;
  bool force = false, resume = false, quiet = false, copy = false;
  app.add_option("study", study_path, "Study file")->required();
  app.add_option("-o,--output", output, "Archive")->required();
  app.add_option("--threads", threads, "Compute threads per rank (0: all cores)");
  app.add_option("--shard", shard, "Shard i/N");
  app.add_option("--prefetch", prefetch, "Batches a rank holds beyond its pipeline (0: one per thread)");
  app.add_flag("--force", force, "Replace an existing archive");
  app.add_flag("--resume", resume, "Continue an existing archive");
  app.add_option("--ranks-per-node", ranks_per_node, "Ranks per node (one writer each)");
  app.add_flag("--copy", copy, "Merge the node shards by copy (default: virtual)");
  app.add_flag("-q,--quiet", quiet, "No output");
  CLI11_PARSE(app, argc, argv);
  try {
    gesweep::ShardSpec spec;
    if (!shard.empty()) spec = gesweep::ParseShard(shard, "--shard");
    gesweep::SweepPlan plan(gesweep::LoadStudy(study_path), spec);
    gesweep::MpiRunOptions options;
    options.output = output;
    options.mode = resume ? gesweep::ArchiveOpenMode::kResume
                          : (force ? gesweep::ArchiveOpenMode::kForce : gesweep::ArchiveOpenMode::kCreate);
    options.threads = threads;
    options.prefetch_batches = prefetch;
    options.ranks_per_node = ranks_per_node;
    options.merge = copy ? gesweep::MergeKind::kCopy : gesweep::MergeKind::kVirtual;
    options.command_line = "mpi_runner_driver " + study_path + " -o " + output;
    options.cancel = &g_cancel;
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    gesweep::MpiFinalizer finalize_after_printing;
    gesweep::MpiSweepReport report;
    try {
      report = gesweep::RunStudyMpi(plan, options);
    } catch (const std::exception& e) {
      std::cerr << "mpi_runner_driver: error: " << e.what() << "\n";
      gesweep::AbortMpi(1);
    }
    // The outcome in the CLI's words (tests/mpi/mpi_test.py reads them from either), rank 0 only.
    if (report.rank == 0) {
      if (report.error_code) {
        std::cerr << "gesweep: error: " << report.error << "\n";
      } else if (!quiet || report.cancelled || report.runs_failed) {
        std::cerr << "mpi_runner_driver: " << report.ranks << " ranks on " << report.nodes
                  << " nodes (runs per rank:";
        for (const auto r : report.runs_per_rank) std::cerr << " " << r;
        std::cerr << "); " << report.runs_ok << " ok, " << report.runs_failed << " failed, "
                  << report.runs_pending << " pending" << (report.merged ? "; merged" : "") << "\n";
        if (report.runs_complete_at_start)
          std::cerr << "mpi_runner_driver: resuming: " << report.runs_complete_at_start
                    << " runs already complete\n";
        if (report.cancelled) std::cerr << "mpi_runner_driver: stopped by a signal; continue with --resume\n";
      }
    }
    if (report.error_code) return report.error_code;
    if (report.cancelled) return 128 + g_signal.load();
    return report.runs_failed > 0 ? 3 : 0;
  } catch (const gesweep::InputError& e) {
    std::cerr << "gesweep: error: " << e.what() << "\n";
    return 2;
  }
}
