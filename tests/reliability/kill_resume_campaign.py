#!/usr/bin/python3
"""Crash-safety campaign (issue 10, docs/reliability.md): SIGKILL a sweep at random moments, check
the archive after every kill, resume it, and compare the result with an uninterrupted sweep run by
run.

    kill_resume_campaign.py GESWEEP [--kills 10] [--seed S] [--threads 2] [--study FILE]

1. An uninterrupted reference sweep of the study (2000 runs of modes + boundary + open loop with time
   series, tests/reliability/kill_campaign.toml); its wall time T sets the scale of the kill moments.
2. `--kills` cycles, each on a fresh archive: start `gesweep run`, SIGKILL it at a moment drawn
   uniformly in [0.02 T, 0.98 T] (from the seed, printed, so a failure replays with --seed), then:
   - the archive opens with h5py (normally, or as a SWMR snapshot), or does not exist yet (killed
     while being set up: nothing under the final name, by design); every run it holds as complete
     equals the reference's, byte for byte, at its own row (no duplicate); no stray file but the
     lock and a temporary .partial;
   - the engine's own reader opens it too (`gesweep merge` of the killed archive must refuse it with
     one line, exit 2, and write nothing; or merge it when the kill came after the sweep closed it),
     and `gesweep query ARCHIVE --describe` describes it (exit 0) when this build has `query`;
   - in every other cycle (seeded) the resume itself is killed at a random moment and checked again;
   - `--resume` runs to the end; the final archive equals the reference: no run missing, none twice,
     every dataset equal bit for bit, attributes equal but for provenance, no stray file.
Exit 0 when every cycle passes; 1 with the reasons otherwise."""
import argparse
import os
import pathlib
import random
import signal
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import archive_tools as tools  # noqa: E402

# Kill moments are drawn in this fraction of the reference sweep's wall time: after process start
# (setup and the first batches included) and before its very end.
KILL_WINDOW = (0.02, 0.98)
# A resume is killed earlier in its (shorter) remaining work.
RESUME_KILL_WINDOW = (0.02, 0.6)
# When the sweep ended before its kill moment (a quiet machine), retry that cycle this many times,
# halving the moment each time.
KILL_RETRIES = 4


class Campaign:
    def __init__(self, binary, study, threads, work):
        self.binary = binary
        self.study = study
        self.threads = threads
        self.work = pathlib.Path(work)
        self.failures = []
        self.kills = 0
        self.query = tools.has_subcommand(binary, "query")

    def run_args(self, archive, resume):
        args = ["run", str(self.study), "-o", str(archive), "--threads", str(self.threads), "-q"]
        return args + (["--resume"] if resume else [])

    def reference(self):
        archive = self.work / "reference.h5"
        start = time.monotonic()
        result = tools.gesweep(self.binary, self.run_args(archive, False), timeout=600)
        elapsed = time.monotonic() - start
        if result.returncode not in (0, 3):
            raise SystemExit(f"reference sweep failed: exit {result.returncode}: {result.stderr.strip()[:400]}")
        self.reference_exit = result.returncode
        self.reference_snapshot = tools.Snapshot(archive)
        tools.compare_final(self.reference_snapshot, self.reference_snapshot, "reference")
        return elapsed

    def kill_at(self, archive, resume, moment_s):
        """Starts a sweep and SIGKILLs it `moment_s` after its start. Returns True when it was killed,
        False when it had already finished."""
        process = tools.start_gesweep(self.binary, self.run_args(archive, resume), self.work / "stderr.txt")
        deadline = time.monotonic() + moment_s
        while time.monotonic() < deadline and process.poll() is None:
            time.sleep(min(0.005, max(0.0, deadline - time.monotonic())))
        if process.poll() is not None:
            return False
        process.send_signal(signal.SIGKILL)
        code = process.wait()
        if code != -signal.SIGKILL:
            return False
        self.kills += 1
        return True

    def check_after_kill(self, archive, label):
        """The state a kill leaves. Returns a short description; records failures."""
        stray = tools.leftovers(self.work, {"reference.h5", "stderr.txt", archive.name, archive.name + ".lock",
                                            archive.name + ".partial"})
        if stray:
            self.failures.append(f"{label}: stray files after the kill: {stray}")
        if not archive.exists():
            state = "killed while setting up (no archive yet)"
            complete = 0
        else:
            try:
                snapshot = tools.Snapshot(archive)
                complete = tools.compare_complete_rows(self.reference_snapshot, snapshot, label)
                state = f"{'snapshot' if snapshot.snapshot else 'closed'} with {complete} complete runs"
            except (OSError, KeyError, ValueError, tools.ArchiveProblem) as error:
                self.failures.append(f"{label}: the archive does not open (or is wrong) after the kill: {error}")
                return "unreadable"
        # The engine's reader on the same file: a killed shard is refused with one line, never a crash.
        merged = self.work / "merged.h5"
        result = tools.gesweep(self.binary, ["merge", str(archive), "-o", str(merged), "-q"])
        lines = result.stderr.strip().splitlines()
        if result.returncode == 2:
            if len(lines) != 1 or merged.exists():
                self.failures.append(f"{label}: gesweep merge of the killed archive: {len(lines)} lines, "
                                     f"output left {merged.exists()}: {result.stderr.strip()[:300]}")
        elif result.returncode != 0 or complete != self.reference_snapshot.run_count:
            self.failures.append(f"{label}: gesweep merge of the killed archive ({state}) exit "
                                 f"{result.returncode}: {result.stderr.strip()[:300]}")
        merged.unlink(missing_ok=True)
        for suffix in (".partial", ".lock"):
            pathlib.Path(str(merged) + suffix).unlink(missing_ok=True)
        # `gesweep query` (when this build has it) describes the killed archive: it opens.
        if self.query and archive.exists():
            result = tools.gesweep(self.binary, ["query", str(archive), "--describe"])
            if result.returncode != 0:
                self.failures.append(f"{label}: gesweep query --describe of the killed archive ({state}): exit "
                                     f"{result.returncode}: {result.stderr.strip()[:300]}")
        return state

    def cycle(self, number, rng, reference_s):
        archive = self.work / f"cycle{number}.h5"
        label = f"cycle {number}"
        notes = []
        # 1. Kill the fresh sweep at a random moment.
        moment = rng.uniform(*KILL_WINDOW) * reference_s
        for attempt in range(KILL_RETRIES + 1):
            if self.kill_at(archive, False, moment):
                break
            notes.append(f"finished before {moment:.2f} s")
            for suffix in ("", ".lock", ".partial"):
                pathlib.Path(str(archive) + suffix).unlink(missing_ok=True)
            moment /= 2
        else:
            self.failures.append(f"{label}: the sweep always finished before its kill moment: make it longer")
            print(f"{label}: " + "; ".join(notes), flush=True)
            return
        notes.append(f"killed at {moment:.2f} s: {self.check_after_kill(archive, label + ' kill 1')}")
        # 2. In every other cycle, kill the resume too.
        if rng.random() < 0.5:
            resume_moment = rng.uniform(*RESUME_KILL_WINDOW) * reference_s
            if self.kill_at(archive, True, resume_moment):
                notes.append(f"resume killed at {resume_moment:.2f} s: "
                             f"{self.check_after_kill(archive, label + ' kill 2')}")
            else:
                notes.append(f"resume finished before {resume_moment:.2f} s")
        # 3. Resume to the end and compare with the reference.
        result = tools.gesweep(self.binary, self.run_args(archive, True), timeout=300)
        if result.returncode != self.reference_exit:
            self.failures.append(f"{label}: --resume exit {result.returncode} (reference {self.reference_exit}): "
                                 f"{result.stderr.strip()[:400]}")
        else:
            try:
                tools.compare_final(self.reference_snapshot, tools.Snapshot(archive), label + " final")
                notes.append("resumed: equal to the reference")
            except (OSError, KeyError, ValueError, tools.ArchiveProblem) as error:
                self.failures.append(f"{label}: final archive: {error}")
        stray = tools.leftovers(self.work, {"reference.h5", "stderr.txt", archive.name})
        if stray:
            self.failures.append(f"{label}: stray files after the resume: {stray}")
        print(f"{label}: " + "; ".join(notes), flush=True)
        for suffix in ("", ".lock", ".partial"):
            pathlib.Path(str(archive) + suffix).unlink(missing_ok=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("gesweep")
    parser.add_argument("--kills", type=int, default=10, help="cycles (each kills a fresh sweep once)")
    parser.add_argument("--seed", type=int, default=None, help="seed of the kill moments (default: the clock)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--study", default=str(pathlib.Path(__file__).resolve().parent / "kill_campaign.toml"))
    args = parser.parse_args()
    seed = args.seed if args.seed is not None else tools.environment_seed("GESWEEP_KILL_SEED", time.time_ns() % 2**31)
    rng = random.Random(seed)
    print(f"kill campaign: seed {seed} (replay: --seed {seed}), {args.kills} cycles, {args.threads} threads")
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="gesweep_kills_") as work:
        campaign = Campaign(os.path.abspath(args.gesweep), pathlib.Path(args.study).resolve(), args.threads, work)
        reference_s = campaign.reference()
        print(f"reference: {campaign.reference_snapshot.run_count} runs in {reference_s:.2f} s "
              f"(exit {campaign.reference_exit})")
        for number in range(args.kills):
            campaign.cycle(number, rng, reference_s)
    for failure in campaign.failures:
        print("FAIL", failure)
    print(f"{campaign.kills} SIGKILLs in {args.kills} cycles, {len(campaign.failures)} failures, "
          f"{time.monotonic() - started:.1f} s (seed {seed})")
    return 1 if campaign.failures or campaign.kills < args.kills else 0


if __name__ == "__main__":
    sys.exit(main())
