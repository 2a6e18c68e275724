#!/usr/bin/python3
"""End-to-end test of the MPI runner (engine/mpi; docs/cluster.md, "MPI").

  mpi_test.py --gesweep build/gesweep --mpirun mpiexec --runner driver --driver build/mpi_runner_driver
  mpi_test.py --gesweep build/gesweep --mpirun mpiexec --runner cli

For each test study, runs it once in a single process (`gesweep run`, the reference) and once under
`mpirun --allow-run-as-root --oversubscribe -n 3` (the runner: tests/mpi/mpi_runner_driver, which
calls RunStudyMpi directly, or `gesweep run --mpi`), and requires:
  - the same exit code (0 all ok, 3 some runs failed: failures are data);
  - archives equal run by run and bit for bit apart from provenance (tests/slurm/compare_archives.py);
  - every rank computed some runs (the work was really spread), the counts adding up to the design;
  - a second MPI run into the existing archive is refused (exit 2, one error line, archive intact);
  - `--resume` of the complete archive runs nothing and leaves it equal to the reference;
  - an MPI run stopped by SIGTERM (a longer study) leaves a resumable archive whose `--resume` under MPI equals the
    reference.
Exit 0 pass, 1 fail, 77 skipped (`--runner cli` while `gesweep run` has no --mpi flag).
"""

import argparse
import hashlib
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
COMPARE = os.path.join(ROOT, "tests", "slurm", "compare_archives.py")
# (study, every rank must get runs): 400 modes runs in 25 batches (milliseconds of work); modes +
# boundary + open loop with series in 24 batches (about a second of work per rank).
STUDIES = [(os.path.join(ROOT, "tests", "slurm", "tiny_study.toml"), False),
           (os.path.join(ROOT, "tests", "mpi", "mpi_study.toml"), True)]
# Long enough (6000 boundary runs, seconds) to be stopped mid-run: mpirun forwards SIGTERM to every
# rank, with a delay of its own.
INTERRUPT_STUDY = os.path.join(ROOT, "tests", "slurm", "requeue_study.toml")
RANKS = 3
# OpenMPI refuses to run as root without these (CI containers run as root), and its shared-memory
# transport's single-copy mechanism (CMA) needs ptrace rights containers often lack.
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none"}
TIMEOUT_S = 240  # one MPI run of a test study takes seconds; this only catches a hang
RANKS_LINE = re.compile(r"runs per rank:((?: \d+)+)\)")


class Failure(Exception):
    pass


def run(command, env=None, check_codes=(0,), timeout=TIMEOUT_S):
    result = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    if check_codes is not None and result.returncode not in check_codes:
        raise Failure(f"{' '.join(command)} exited {result.returncode} (expected {check_codes})\n"
                      f"stdout:\n{result.stdout}\nstderr:\n{result.stderr}")
    return result


def mpi_env():
    env = dict(os.environ)
    env.update(MPI_ENV)
    return env


def mpi_command(args, study, output, extra=()):
    prefix = [args.mpirun, "--allow-run-as-root", "--oversubscribe", "-n", str(RANKS)]
    if args.runner == "cli":
        return prefix + [args.gesweep, "run", study, "-o", output, "--mpi", "--threads", "1", *extra]
    return prefix + [args.driver, study, "-o", output, "--threads", "1", *extra]


def compare(reference, candidate):
    result = subprocess.run(["/usr/bin/python3", COMPARE, reference, candidate], cwd=ROOT, capture_output=True,
                            text=True)
    if result.returncode != 0:
        raise Failure(f"{candidate} differs from {reference}:\n{result.stdout}{result.stderr}")


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def design_runs(args, study):
    import json
    out = run([args.gesweep, "run", study, "-o", "unused.h5", "--dry-run", "--format", "json", "--threads", "1"])
    return json.loads(out.stdout)["design_runs"]


def check_study(args, study, spread_required, work):
    name = os.path.splitext(os.path.basename(study))[0]
    reference = os.path.join(work, name + "-reference.h5")
    candidate = os.path.join(work, name + "-mpi.h5")
    ref = run([args.gesweep, "run", study, "-o", reference, "--threads", "2", "-q"], check_codes=(0, 3))
    mpi = run(mpi_command(args, study, candidate), env=mpi_env(), check_codes=(0, 3))
    if mpi.returncode != ref.returncode:
        raise Failure(f"{name}: MPI run exited {mpi.returncode}, single process {ref.returncode}\n{mpi.stderr}")
    compare(reference, candidate)
    match = RANKS_LINE.search(mpi.stderr)
    if not match:
        raise Failure(f"{name}: no 'runs per rank' in the MPI run's summary:\n{mpi.stderr}")
    per_rank = [int(x) for x in match.group(1).split()]
    total = design_runs(args, study)
    if len(per_rank) != RANKS or sum(per_rank) != total:
        raise Failure(f"{name}: runs per rank {per_rank}: expected {RANKS} ranks, {total} runs in all")
    # Spread for real: a study of seconds must reach every rank. (A study of milliseconds, like the
    # 400 modes runs, may legitimately be done by rank 0 before a descheduled rank asks.)
    if spread_required and min(per_rank) <= 0:
        raise Failure(f"{name}: runs per rank {per_rank}: a rank got no batch")
    print(f"{name}: {total} runs, exit {mpi.returncode}, runs per rank {per_rank}: equal to the single-process "
          f"archive")

    # An existing archive is refused (the person's mistake, found by rank 0 before anything runs).
    before = digest(candidate)
    refused = run(mpi_command(args, study, candidate), env=mpi_env(), check_codes=(2,))
    errors = [line for line in refused.stderr.splitlines() if line.startswith("gesweep: error")]
    if len(errors) != 1 or digest(candidate) != before:
        raise Failure(f"{name}: existing archive: expected one error line and the archive untouched, got "
                      f"{errors}\n{refused.stderr}")

    # --resume of a complete archive: nothing to hand out; every rank must still finish.
    resumed = run(mpi_command(args, study, candidate, ["--resume"]), env=mpi_env(), check_codes=(0, 3))
    if "runs per rank: 0 0 0)" not in resumed.stderr:
        raise Failure(f"{name}: --resume of a complete archive ran something:\n{resumed.stderr}")
    compare(reference, candidate)
    print(f"{name}: existing archive refused; --resume of a complete archive runs nothing")


def check_interrupted(args, study, work):
    """SIGTERM to mpirun mid-run (forwarded to every rank), then --resume under MPI: equal to reference."""
    reference = os.path.join(work, "interrupted-reference.h5")
    run([args.gesweep, "run", study, "-o", reference, "--threads", "2", "-q"], check_codes=(0, 3))
    candidate = os.path.join(work, "interrupted.h5")
    # Two attempts: on a loaded machine mpirun may forward the signal only after the run has ended.
    for attempt in range(2):
        if os.path.exists(candidate):
            os.remove(candidate)
        process = subprocess.Popen(mpi_command(args, study, candidate), cwd=ROOT, env=mpi_env(),
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        # Rank 0 creates the archive once every rank has built its plan and installed its handlers.
        deadline = time.monotonic() + TIMEOUT_S
        while not os.path.exists(candidate) and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(args.interrupt_after_s / (attempt + 1))
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=TIMEOUT_S)
        if "continue with --resume" in stderr:
            break
        if "runs per rank" not in stderr:  # neither stopped cleanly nor finished: a real failure
            break
    if "continue with --resume" not in stderr:
        raise Failure(f"SIGTERM after the archive appeared did not stop the MPI run cleanly "
                      f"(exit {process.returncode}):\n{stderr}")
    resumed = run(mpi_command(args, study, candidate, ["--resume"]), env=mpi_env(), check_codes=(0, 3))
    if "resuming:" not in resumed.stderr:
        raise Failure(f"the resumed run did not report resuming:\n{resumed.stderr}")
    compare(reference, candidate)
    print(f"SIGTERM mid-run: exit {process.returncode}, archive closed; --resume under MPI: equal to the reference")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gesweep", required=True)
    parser.add_argument("--mpirun", default="mpirun")
    parser.add_argument("--runner", choices=("driver", "cli"), default="driver")
    parser.add_argument("--driver")
    parser.add_argument("--interrupt-after-s", type=float, default=0.5)
    args = parser.parse_args()
    if args.runner == "driver" and not args.driver:
        parser.error("--runner driver needs --driver")
    if args.runner == "cli":
        help_text = run([args.gesweep, "run", "--help"]).stdout
        if "--mpi" not in help_text:
            print("FAIL: `gesweep run --help` lists no --mpi flag, though gesweep was built with MPI")
            return 1
    try:
        with tempfile.TemporaryDirectory(prefix="gesweep-mpi-") as work:
            for study, spread_required in STUDIES:
                check_study(args, study, spread_required, work)
            check_interrupted(args, INTERRUPT_STUDY, work)
    except (Failure, subprocess.TimeoutExpired) as e:
        print(f"FAIL: {e}", file=sys.stderr)
        return 1
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
