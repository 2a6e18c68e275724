// gesweep.run (a study into an archive) and the archive check behind gesweep.open_archive.
#include "engine/python/support.h"

namespace gesweep::python {

// ---------------------------------------------------------------- run

py::dict Run(const std::string& study_path, const std::string& archive_path, int threads, py::object progress,
             bool resume, bool force, const std::string& shard_text) {
  if (resume && force)
    throw InputError(kArguments, "force", "True", "cannot be combined with resume=True (choose one)");
  if (threads < 0 || threads > 4096)
    throw InputError(kArguments, "threads", std::to_string(threads),
                     "expected 1 to 4096 worker threads, or None");
  ShardSpec shard;
  if (!shard_text.empty()) shard = ParseShard(shard_text, "shard");
  Study study = LoadStudy(study_path);
  CheckOutputPath(archive_path, OutputKind::kFile, study.inputs, "archive_path",
                  {archive_path + ".partial", archive_path + ".lock"});
  SweepPlan plan(std::move(study), shard);
  const int workers = threads > 0 ? threads : tbb::info::default_concurrency();
  ArchiveOpenReport opened;
  std::unique_ptr<ArchiveWriter> writer;
  std::string call = "gesweep.run(" + Repr(py::str(study_path)) + ", " + Repr(py::str(archive_path));
  if (threads > 0) call += ", threads=" + std::to_string(threads);
  if (!shard_text.empty()) call += ", shard=" + Repr(py::str(shard_text));
  if (resume) call += ", resume=True";
  if (force) call += ", force=True";
  call += ")";
  {
    py::gil_scoped_release release;
    writer = ArchiveWriter::Open(
        archive_path, plan, RunProvenance{call, workers},
        resume ? ArchiveOpenMode::kResume : (force ? ArchiveOpenMode::kForce : ArchiveOpenMode::kCreate),
        &opened);
  }
  SweepProgress state;
  state.runs_skipped = opened.runs_complete;
  state.runs_to_do = plan.run_count() - opened.runs_complete;
  SweepOutcome outcome;
  const auto start = std::chrono::steady_clock::now();
  auto tick = [&] {
    if (!progress.is_none()) progress(state.runs_done.load(), state.runs_to_do.load());
  };
  std::exception_ptr interrupted;
  try {
    RunInterruptible(
        [&](const std::atomic<bool>* cancel) {
          RunnerOptions options;
          options.threads = workers;
          options.cancel = cancel;
          outcome = RunSweep(plan, opened.pending_blocks, *writer, options, &state);
        },
        tick);
  } catch (py::error_already_set&) {
    interrupted = std::current_exception();  // KeyboardInterrupt, or the callback's exception
  }
  {
    py::gil_scoped_release release;
    writer->Finish();  // closes the archive: what is complete stays for resume=True
  }
  if (interrupted) std::rethrow_exception(interrupted);
  tick();
  py::dict out;
  out["archive"] = archive_path;
  out["runs"] = plan.run_count();
  out["runs_run"] = state.runs_done.load();
  out["runs_ok"] = writer->runs_ok();
  out["runs_failed"] = writer->runs_failed();
  out["runs_pending"] = writer->runs_pending();
  out["cancelled"] = outcome.cancelled;
  out["threads"] = workers;
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

/// The check every gesweep command makes of an archive before it reads a value (ArchiveReader::Open:
/// the file, its layout, a virtual archive's sources and theirs), for open_archive to make before h5py
/// reads anything: {"snapshot": a sweep is writing it or was killed, "virtual": bool, "notes": what
/// could not be checked}; InputError, in the command's words, naming the file and why otherwise.
py::dict CheckArchive(const std::string& path) {
  bool snapshot = false, is_virtual = false;
  std::vector<std::string> notes;
  {
    py::gil_scoped_release release;
    ArchiveReader reader = ArchiveReader::Open(path);
    snapshot = reader.snapshot();
    is_virtual = reader.is_virtual();
    notes = reader.notes();
  }
  py::dict out;
  out["snapshot"] = snapshot;
  out["virtual"] = is_virtual;
  out["notes"] = notes;
  return out;
}

}  // namespace gesweep::python
