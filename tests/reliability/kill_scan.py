#!/usr/bin/python3
"""Kill scan (issue 10, docs/reliability.md): SIGKILL a short sweep at EVERY moment of its life, a
millisecond or so apart, where the random campaign (kill_resume_campaign.py) lands only by luck on
the short windows: the archive's creation, its rename into place, the switch to SWMR mode, the end of
the sweep, and the start of a resume.

    kill_scan.py GESWEEP [--steps 45]

Phase 1, a fresh sweep (64 runs of modes, about 0.1 s): for each kill moment from 0 to 1.2 T (T its
uninterrupted wall time), start it on a fresh archive, SIGKILL it, then:
  - the archive does not exist (killed before it was put in place), or it opens with h5py, normally or
    as a SWMR snapshot, and every run it calls complete equals the reference's;
  - `--resume` completes it (exit 0) and it equals the uninterrupted archive run by run, bit for bit.
Phase 2, the resume of a sweep stopped cleanly by SIGTERM (its archive closed with runs pending): the
same kill moments over the resume's start, each time on a copy of the stopped archive, then the same
checks.
Exit 0 when every kill leaves an archive that opens and resumes; 1 with the failing moments."""
import argparse
import os
import pathlib
import shutil
import signal
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import archive_tools as tools  # noqa: E402

AIRCRAFT = tools.source_root() / "studies" / "aircraft" / "ance.toml"
# Phase 1: cheap runs, so the process's life is mostly its setup and its finish.
FAST_STUDY = f"""format_version = 1
name = "kill_scan_fast"
aircraft = "{AIRCRAFT}"
[analyses.modes]
[output]
chunk_runs = 16
[parameters]
speed_mps = 32.0208
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
linspace = [1.0, 13.0, 64]
"""
# Phase 2: slower runs (boundary), so SIGTERM can stop it half-way.
STOPPABLE_STUDY = f"""format_version = 1
name = "kill_scan_stoppable"
aircraft = "{AIRCRAFT}"
[analyses.modes]
[analyses.boundary]
# The former sampled search (about 1 ms a run, 20x the certified finder): the runs must last long
# enough for the test to interrupt the sweep.
method = "sampled"
[output]
chunk_runs = 16
[parameters]
height_m = 2.0
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [28.0, 55.0, 256]
"""
# Kill moments span this multiple of the uninterrupted wall time (the end included).
SCAN_SPAN = 1.2
# Phase 2 scans the resume's start: this multiple of the fast sweep's wall time (a process start,
# the study and the archive opened).
RESUME_SCAN_SPAN = 1.5


def clear(archive):
    for suffix in ("", ".lock", ".partial"):
        pathlib.Path(str(archive) + suffix).unlink(missing_ok=True)


class Scan:
    def __init__(self, binary, work):
        self.binary = binary
        self.work = pathlib.Path(work)
        self.failures = []
        self.outcomes = {}

    def run(self, study, archive, resume=False):
        args = ["run", str(study), "-o", str(archive), "-q", "--threads", "2"] + (["--resume"] if resume else [])
        return tools.gesweep(self.binary, args, timeout=300)

    def reference(self, study, name):
        archive = self.work / name
        start = time.monotonic()
        result = self.run(study, archive)
        elapsed = time.monotonic() - start
        if result.returncode != 0:
            raise SystemExit(f"reference {name}: exit {result.returncode}: {result.stderr.strip()[:300]}")
        return tools.Snapshot(archive), elapsed

    def kill_and_check(self, study, archive, resume, moment_s, reference, label):
        args = ["run", str(study), "-o", str(archive), "-q", "--threads", "2"] + (["--resume"] if resume else [])
        process = tools.start_gesweep(self.binary, args, self.work / "stderr.txt")
        time.sleep(moment_s)
        process.send_signal(signal.SIGKILL)
        killed = process.wait() == -signal.SIGKILL
        state = "killed" if killed else "finished"
        if archive.exists():
            try:
                snapshot = tools.Snapshot(archive)
                tools.compare_complete_rows(reference, snapshot, label)
                state += ", opens" + (" (snapshot)" if snapshot.snapshot else "")
            except (OSError, KeyError, ValueError, tools.ArchiveProblem) as error:
                state += ", does not open"
                self.failures.append(f"{label}: after the kill the archive does not open (or is wrong): "
                                     f"{str(error)[:200]}")
        else:
            state += ", no archive yet"
        result = self.run(study, archive, resume=True)
        if result.returncode != 0:
            state += f", resume exit {result.returncode}"
            self.failures.append(f"{label}: --resume exit {result.returncode}: {result.stderr.strip()[:300]}")
        else:
            try:
                tools.compare_final(reference, tools.Snapshot(archive), label)
                state += ", resumed equal"
            except (OSError, KeyError, ValueError, tools.ArchiveProblem) as error:
                state += ", resumed different"
                self.failures.append(f"{label}: resumed archive: {error}")
        self.outcomes.setdefault(state, []).append(round(moment_s * 1000, 1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("gesweep")
    parser.add_argument("--steps", type=int, default=45, help="kill moments per phase")
    args = parser.parse_args()
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="gesweep_kill_scan_") as work:
        work = pathlib.Path(work)
        scan = Scan(os.path.abspath(args.gesweep), work)
        fast = work / "fast.toml"
        fast.write_text(FAST_STUDY)
        stoppable = work / "stoppable.toml"
        stoppable.write_text(STOPPABLE_STUDY)

        fast_reference, fast_s = scan.reference(fast, "fast_reference.h5")
        print(f"phase 1: fresh sweep of {fast_reference.run_count} runs, {fast_s * 1000:.0f} ms uninterrupted; "
              f"{args.steps} kills from 0 to {SCAN_SPAN * fast_s * 1000:.0f} ms")
        archive = work / "fast.h5"
        for step in range(args.steps):
            clear(archive)
            moment = SCAN_SPAN * fast_s * step / (args.steps - 1)
            scan.kill_and_check(fast, archive, False, moment, fast_reference, f"fresh sweep killed at "
                                f"{moment * 1000:.1f} ms")
        phase1 = scan.outcomes
        scan.outcomes = {}

        stoppable_reference, stoppable_s = scan.reference(stoppable, "stoppable_reference.h5")
        stopped = work / "stopped.h5"
        for fraction in (0.5, 0.3, 0.2, 0.1, 0.05):
            clear(stopped)
            process = tools.start_gesweep(scan.binary, ["run", str(stoppable), "-o", str(stopped), "-q", "--threads",
                                                        "2"], work / "stderr.txt")
            # The signal handler is in place once the archive exists (gesweep run installs it before it
            # opens the archive). Under a sanitizer the study's loading takes half the reference time, so
            # a moment counted from the start could fall before it (the process then dies of the signal).
            launched = time.monotonic()
            while not stopped.exists() and process.poll() is None:
                time.sleep(0.001)
            time.sleep(fraction * max(0.0, stoppable_s - (time.monotonic() - launched)))
            process.send_signal(signal.SIGTERM)
            if process.wait() == 128 + signal.SIGTERM:
                break
        else:
            raise SystemExit("phase 2: could not stop the sweep half-way with SIGTERM")
        pending = int((tools.Snapshot(stopped).status == 0).sum())
        print(f"phase 2: resume of a sweep stopped by SIGTERM ({pending} of {stoppable_reference.run_count} runs "
              f"pending); {args.steps} kills from 0 to {RESUME_SCAN_SPAN * fast_s * 1000:.0f} ms")
        archive = work / "resumed.h5"
        for step in range(args.steps):
            clear(archive)
            shutil.copyfile(stopped, archive)
            moment = RESUME_SCAN_SPAN * fast_s * step / (args.steps - 1)
            scan.kill_and_check(stoppable, archive, True, moment, stoppable_reference,
                                f"resume killed at {moment * 1000:.1f} ms")
        phase2 = scan.outcomes

    for title, outcomes in (("phase 1", phase1), ("phase 2", phase2)):
        for state, moments in sorted(outcomes.items()):
            print(f"  {title}: {len(moments):3d} x {state}: at {moments[:8]}{' ...' if len(moments) > 8 else ''} ms")
    for failure in scan.failures:
        print("FAIL", failure)
    print(f"{2 * args.steps} kills, {len(scan.failures)} failures, {time.monotonic() - started:.1f} s")
    return 1 if scan.failures else 0


if __name__ == "__main__":
    sys.exit(main())
