#!/usr/bin/python3
"""Concurrent readers (issue 10, docs/reliability.md): reading an archive while a sweep writes it gives
a consistent snapshot of the complete runs, or a clear "archive in use" answer; never a crash, never
garbage; and a reader never breaks the writer.

    concurrent_readers.py GESWEEP

1. A reference sweep of tests/reliability/concurrent_readers.toml (2 threads).
2. The same sweep on one thread (a thread count must not change a bit), read all the while, in turn, by
   - h5py in SWMR-read mode, as docs/sweep.md tells users to;
   - h5py as a user who does not know about SWMR: a normal open, then SWMR when that is refused;
   - the engine's reader through the CLI: `gesweep merge` of the live archive must refuse it with one
     line (exit 2) and write nothing;
   - `gesweep query ARCHIVE --describe`, when this build has it: exit 0, or exit 2 with one line.
   Every archive a reader opens must hold only runs equal to the reference's, byte for byte, at their
   own rows, and a run complete in one snapshot stays complete in the next. An open may be refused
   only with HDF5's "in use" reasons (open for writing, not yet in SWMR mode, locked). The sweep must
   end with exit 0 and an archive equal to the reference.
3. A reader holding a stopped archive open while `--resume` starts: the resume must either work or
   refuse with one line saying the archive is in use (exit 2); never fail half-way (exit 1).
Exit 0 when all holds; 1 with the reasons otherwise."""
import argparse
import os
import pathlib
import shutil
import signal
import sys
import tempfile
import time

import h5py

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import archive_tools as tools  # noqa: E402

STUDY = pathlib.Path(__file__).resolve().parent / "concurrent_readers.toml"
# HDF5's reasons for refusing an open while a writer has the file: the answers a reader may get
# instead of a snapshot.
IN_USE_REASONS = ("already open for write", "not already open for SWMR writing", "unable to lock file")
# Fewer snapshots than this with some but not all runs complete means the sweep was too short to
# observe: the test would prove nothing.
MINIMUM_PARTIAL_SNAPSHOTS = 3
# The stopped archive of part 3 is stopped (SIGTERM) once this many runs are complete.
STOP_AFTER_RUNS = 64


class Readers:
    def __init__(self, binary, work, reference):
        self.binary = binary
        self.work = pathlib.Path(work)
        self.reference = reference
        self.failures = []
        self.counts = {}
        self.previous_complete = None
        self.partial_snapshots = 0
        self.query = tools.has_subcommand(binary, "query")

    def count(self, what):
        self.counts[what] = self.counts.get(what, 0) + 1

    def check_snapshot(self, snapshot, reader):
        complete = tools.compare_complete_rows(self.reference, snapshot, reader)
        rows = set(snapshot.complete().tolist())
        if self.previous_complete is not None and not self.previous_complete <= rows:
            lost = sorted(self.previous_complete - rows)[:5]
            self.failures.append(f"{reader}: runs complete in an earlier snapshot are no longer complete: {lost}")
        self.previous_complete = rows
        if 0 < complete < self.reference.run_count:
            self.partial_snapshots += 1

    def h5py_reader(self, archive, swmr_only):
        reader = "h5py swmr" if swmr_only else "h5py plain-then-swmr"
        try:
            if swmr_only:
                with h5py.File(archive, "r", swmr=True):
                    pass
            snapshot = tools.Snapshot(archive)  # plain open first, SWMR when refused
        except FileNotFoundError:
            self.count("not created yet")
            return
        except OSError as error:
            if any(reason in str(error) for reason in IN_USE_REASONS):
                self.count(f"{reader}: in use")
                return
            self.failures.append(f"{reader}: open failed for another reason than 'in use': {error}")
            return
        except tools.ArchiveProblem as error:
            self.failures.append(f"{reader}: {error}")
            return
        try:
            self.check_snapshot(snapshot, reader)
            self.count(f"{reader}: snapshot")
        except tools.ArchiveProblem as error:
            self.failures.append(f"{reader}: garbage in the snapshot: {error}")

    def engine_reader(self, archive):
        merged = self.work / "merged.h5"
        result = tools.gesweep(self.binary, ["merge", str(archive), "-o", str(merged), "-q"])
        lines = result.stderr.strip().splitlines()
        if result.returncode == 2 and len(lines) == 1 and not merged.exists():
            self.count("gesweep merge: refused")
        elif result.returncode == 0:
            self.count("gesweep merge: merged (the sweep had ended)")
        else:
            self.failures.append(f"gesweep merge of the live archive: exit {result.returncode}, {len(lines)} lines, "
                                 f"output left {merged.exists()}: {result.stderr.strip()[:300]}")
        merged.unlink(missing_ok=True)

    def query_reader(self, archive):
        result = tools.gesweep(self.binary, ["query", str(archive), "--describe"])
        lines = result.stderr.strip().splitlines()
        if result.returncode == 0:
            self.count("gesweep query: answered")
        elif result.returncode == 2 and len(lines) == 1:
            self.count("gesweep query: refused")
        else:
            self.failures.append(f"gesweep query of the live archive: exit {result.returncode}: "
                                 f"{result.stderr.strip()[:300]}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("gesweep")
    args = parser.parse_args()
    binary = os.path.abspath(args.gesweep)
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="gesweep_readers_") as work:
        work = pathlib.Path(work)
        reference_path = work / "reference.h5"
        result = tools.gesweep(binary, ["run", str(STUDY), "-o", str(reference_path), "-q", "--threads", "2"],
                               timeout=600)
        if result.returncode != 0:
            raise SystemExit(f"reference sweep: exit {result.returncode}: {result.stderr.strip()[:300]}")
        reference = tools.Snapshot(reference_path)
        readers = Readers(binary, work, reference)

        # 2. Read while it writes.
        archive = work / "live.h5"
        process = tools.start_gesweep(binary, ["run", str(STUDY), "-o", str(archive), "-q", "--threads", "1"],
                                      work / "stderr.txt")
        turn = 0
        while process.poll() is None:
            kind = turn % (4 if readers.query else 3)
            if kind == 0:
                readers.h5py_reader(archive, swmr_only=True)
            elif kind == 1:
                readers.h5py_reader(archive, swmr_only=False)
            elif kind == 2:
                readers.engine_reader(archive)
            else:
                readers.query_reader(archive)
            turn += 1
        if process.returncode != 0:
            readers.failures.append(f"the sweep read by others ended with exit {process.returncode}: "
                                    f"{tools.describe_stderr(work / 'stderr.txt')}")
        else:
            try:
                tools.compare_final(reference, tools.Snapshot(archive), "the sweep read by others (1 thread)")
            except (OSError, tools.ArchiveProblem) as error:
                readers.failures.append(str(error))
        if readers.partial_snapshots < MINIMUM_PARTIAL_SNAPSHOTS:
            readers.failures.append(f"only {readers.partial_snapshots} snapshots caught the sweep half-way: "
                                    "make the study longer")

        # 3. A reader holds a stopped archive open while a resume starts.
        stopped = work / "stopped.h5"
        process = tools.start_gesweep(binary, ["run", str(STUDY), "-o", str(stopped), "-q", "--threads", "2"],
                                      work / "stderr.txt")
        while process.poll() is None:  # stop it once some batches are on disk
            try:
                if tools.Snapshot(stopped).complete().size >= STOP_AFTER_RUNS:
                    break
            except (OSError, KeyError, tools.ArchiveProblem):
                pass
            time.sleep(0.02)
        process.send_signal(signal.SIGTERM)
        code = process.wait()
        if code == 128 + signal.SIGTERM:
            pristine = work / "stopped_copy.h5"
            shutil.copyfile(stopped, pristine)
            for mode in ("plain", "swmr"):
                shutil.copyfile(pristine, stopped)
                handle = h5py.File(stopped, "r", swmr=(mode == "swmr"))
                try:
                    result = tools.gesweep(binary, ["run", str(STUDY), "-o", str(stopped), "-q", "--resume",
                                                    "--threads", "2"], timeout=600)
                finally:
                    handle.close()
                lines = result.stderr.strip().splitlines()
                if result.returncode == 0:
                    readers.count(f"resume under a {mode} reader: worked")
                elif result.returncode == 2 and len(lines) == 1 and "in use" in lines[0]:
                    readers.count(f"resume under a {mode} reader: refused as in use")
                else:
                    readers.failures.append(f"--resume while an h5py {mode} reader holds the archive: exit "
                                            f"{result.returncode} (expected 0, or 2 with one 'archive in use' "
                                            f"line): {result.stderr.strip()[:300]}")
        else:
            readers.failures.append(f"could not stop a sweep with SIGTERM for the reader-vs-resume case (exit {code})")

    for what, n in sorted(readers.counts.items()):
        print(f"  {n:4d} x {what}")
    print(f"  {readers.partial_snapshots} snapshots with the sweep half-way"
          f"{'' if readers.query else '; gesweep query not in this build (not tested)'}")
    for failure in readers.failures:
        print("FAIL", failure)
    print(f"{len(readers.failures)} failures, {time.monotonic() - started:.1f} s")
    return 1 if readers.failures else 0


if __name__ == "__main__":
    sys.exit(main())
