#!/usr/bin/python3
"""End-to-end test of MPI as the sweep's transport (engine/mpi; docs/cluster.md, "MPI").

  mpi_test.py --gesweep build/gesweep --mpirun mpiexec --runner driver --driver build/mpi_runner_driver
  mpi_test.py --gesweep build/gesweep --mpirun mpiexec --runner cli

For each test study, runs it once in a single process (`gesweep run`, the reference) and under
`mpirun --allow-run-as-root --oversubscribe -n 4` (tests/mpi/mpi_runner_driver, which calls
RunStudyMpi directly, or `gesweep run --mpi`), and requires:
  - 4 ranks as 2 "nodes" (GESWEEP_RANKS_PER_NODE=2 for the driver, --ranks-per-node 2 for the CLI):
    exactly 2 node shards and a virtual archive (h5py sees virtual datasets) equal to the reference
    dataset by dataset, provenance excluded (tests/slurm/compare_archives.py); the same exit code
    (0, or 3 when some runs failed: failures are data); every rank computed runs, adding up to the
    design;
  - the same 4 ranks as 1 node (one writer): one node shard, equal to the reference;
  - 2 nodes merged by copy (--merge copy / --copy): a self-contained archive (no virtual dataset),
    equal to the reference;
  - a second MPI run into the existing archive is refused (exit 2, one error line, archive intact);
  - `--resume` of the complete run computes nothing and leaves the archive equal to the reference;
  - an MPI run stopped by SIGTERM (a longer study) leaves resumable node shards whose `--resume`
    under MPI equals the reference;
  - an MPI run SIGKILLed mid-run (mpirun and every rank, its process group) leaves node shards that
    open as snapshots (h5py, swmr=True) holding only correct complete runs, and `--resume` under MPI
    completes them into an archive equal to the reference (crash safety per node writer).
Exit 0 pass, 1 fail.
"""

import argparse
import hashlib
import glob
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
RANKS = 4
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


def mpi_command(args, study, output, extra=(), ranks_per_node=2, copy=False):
    """4 ranks as `ranks_per_node`-rank nodes: the CLI takes --ranks-per-node, the driver the
    environment variable GESWEEP_RANKS_PER_NODE (both ways are tested)."""
    prefix = [args.mpirun, "--allow-run-as-root", "--oversubscribe", "-n", str(RANKS)]
    if args.runner == "cli":
        merge = ["--merge", "copy"] if copy else []
        return prefix + [args.gesweep, "run", study, "-o", output, "--mpi", "--threads", "1",
                         "--ranks-per-node", str(ranks_per_node), *merge, *extra]
    return prefix + ["-x", f"GESWEEP_RANKS_PER_NODE={ranks_per_node}", args.driver, study, "-o", output,
                     "--threads", "1", *(["--copy"] if copy else []), *extra]


def node_shards(output, nodes):
    stem = output[:-3] if output.endswith(".h5") else output
    return [f"{stem}.node{k}-of-{nodes}.h5" for k in range(nodes)]


def check_layout(name, output, nodes, virtual):
    """`nodes` node shards beside `output`, and `output` virtual or self-contained."""
    import glob
    import h5py
    stem = output[:-3] if output.endswith(".h5") else output
    found = sorted(glob.glob(glob.escape(stem) + ".node*-of-*.h5"))
    if found != sorted(node_shards(output, nodes)):
        raise Failure(f"{name}: expected node shards {node_shards(output, nodes)}, found {found}")
    with h5py.File(output, "r") as f:
        is_virtual = f["runs/status"].is_virtual
        if is_virtual != virtual:
            raise Failure(f"{name}: {output} is {'virtual' if is_virtual else 'self-contained'}, expected "
                          f"{'virtual' if virtual else 'self-contained'}")


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
    ref = run([args.gesweep, "run", study, "-o", reference, "--threads", "2", "-q"], check_codes=(0, 3))
    total = design_runs(args, study)
    results = {}
    for label, nodes, copy in (("2 nodes, virtual", 2, False), ("1 node", 1, False), ("2 nodes, copy", 2, True)):
        candidate = os.path.join(work, f"{name}-mpi-{nodes}-{'copy' if copy else 'virtual'}.h5")
        mpi = run(mpi_command(args, study, candidate, ranks_per_node=RANKS // nodes, copy=copy), env=mpi_env(),
                  check_codes=(0, 3))
        if mpi.returncode != ref.returncode:
            raise Failure(f"{name}, {label}: MPI run exited {mpi.returncode}, single process {ref.returncode}\n"
                          f"{mpi.stderr}")
        check_layout(f"{name}, {label}", candidate, nodes, virtual=not copy)
        compare(reference, candidate)
        match = RANKS_LINE.search(mpi.stderr)
        if not match:
            raise Failure(f"{name}, {label}: no 'runs per rank' in the MPI run's summary:\n{mpi.stderr}")
        per_rank = [int(x) for x in match.group(1).split()]
        if len(per_rank) != RANKS or sum(per_rank) != total:
            raise Failure(f"{name}, {label}: runs per rank {per_rank}: expected {RANKS} ranks, {total} runs in all")
        # Spread for real: a study of seconds must reach every rank. (A study of milliseconds, like
        # the 400 modes runs, may legitimately be done by some ranks before a descheduled rank asks.)
        if spread_required and min(per_rank) <= 0:
            raise Failure(f"{name}, {label}: runs per rank {per_rank}: a rank got no batch")
        results[label] = (candidate, per_rank)
        print(f"{name}, {label}: {total} runs, exit {mpi.returncode}, runs per rank {per_rank}: equal to the "
              f"single-process archive")

    candidate = results["2 nodes, virtual"][0]
    # An existing archive is refused (the person's mistake, found by rank 0 before anything runs).
    before = digest(candidate)
    refused = run(mpi_command(args, study, candidate), env=mpi_env(), check_codes=(2,))
    errors = [line for line in refused.stderr.splitlines() if line.startswith("gesweep: error")]
    if len(errors) != 1 or digest(candidate) != before:
        raise Failure(f"{name}: existing archive: expected one error line and the archive untouched, got "
                      f"{errors}\n{refused.stderr}")

    # --resume of a complete run: nothing to hand out; every rank must still finish, and the
    # virtual archive is made again over the same node shards.
    resumed = run(mpi_command(args, study, candidate, ["--resume"]), env=mpi_env(), check_codes=(0, 3))
    if "runs per rank: 0 0 0 0)" not in resumed.stderr:
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
        # The writers create their node shards once every rank has built its plan and installed its
        # handlers (the merged archive appears only at the end).
        first_shard = node_shards(candidate, 2)[0]
        for shard in node_shards(candidate, 2):
            if os.path.exists(shard):
                os.remove(shard)
        deadline = time.monotonic() + TIMEOUT_S
        while not os.path.exists(first_shard) and process.poll() is None and time.monotonic() < deadline:
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
    check_layout("interrupted", candidate, 2, virtual=True)
    if "resuming:" not in resumed.stderr:
        raise Failure(f"the resumed run did not report resuming:\n{resumed.stderr}")
    compare(reference, candidate)
    print(f"SIGTERM mid-run: exit {process.returncode}, archive closed; --resume under MPI: equal to the reference")


def kill_every_rank(output):
    """SIGKILLs every live process whose command line names `output` and waits until none is left.
    The ranks are not all in mpirun's process group (OpenMPI's daemon starts them), so killing the
    group can leave ranks running that hold their node shard's lock; a --resume started then is
    refused ("archive in use"). A zombie has released its locks, so it counts as gone."""
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline:
        alive = []
        for proc in glob.glob("/proc/[0-9]*"):
            try:
                with open(proc + "/cmdline", "rb") as f:
                    cmdline = f.read()
                with open(proc + "/stat") as f:
                    state = f.read().rsplit(")", 1)[1].split()[0]
            except OSError:
                continue
            if output.encode() in cmdline and state != "Z":
                alive.append(int(proc.rsplit("/", 1)[1]))
        if not alive:
            return
        for pid in alive:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        time.sleep(0.02)
    raise Failure(f"processes writing {output} still alive {TIMEOUT_S} s after SIGKILL")


def check_killed(args, study, work):
    """SIGKILL to mpirun and every rank mid-run, then --resume under MPI: equal to the reference."""
    import h5py
    import numpy as np
    reference = os.path.join(work, "interrupted-reference.h5")  # made by check_interrupted
    candidate = os.path.join(work, "killed.h5")
    shards = node_shards(candidate, 2)
    process = subprocess.Popen(mpi_command(args, study, candidate), cwd=ROOT, env=mpi_env(), start_new_session=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + TIMEOUT_S
    complete = 0
    while process.poll() is None and time.monotonic() < deadline and complete < 500:
        time.sleep(0.05)
        try:
            complete = 0
            for shard in shards:
                with h5py.File(shard, "r", swmr=True) as f:
                    complete += int((f["runs/status"][()] != 0).sum())
        except (OSError, KeyError):
            complete = 0
    os.killpg(os.getpgid(process.pid), signal.SIGKILL)
    process.wait(timeout=TIMEOUT_S)
    kill_every_rank(candidate)
    if complete < 500:
        raise Failure(f"the MPI run ended (or wrote nothing) before it could be killed ({complete} runs complete)")
    with h5py.File(reference, "r") as ref:
        expected = ref["results/boundary/height_m"][()]
        for shard in shards:
            with h5py.File(shard, "r", swmr=True) as f:
                first = int(f.attrs["first_run"])
                status = f["runs/status"][()]
                done = status != 0
                got = f["results/boundary/height_m"][()][done]
                want = expected[first:first + len(status)][done]
                if got.tobytes() != want.tobytes():
                    raise Failure(f"{shard}: complete runs differ from the reference after SIGKILL")
    resumed = run(mpi_command(args, study, candidate, ["--resume"]), env=mpi_env(), check_codes=(0, 3))
    if "resuming:" not in resumed.stderr:
        raise Failure(f"the resumed run did not report resuming:\n{resumed.stderr}")
    check_layout("killed", candidate, 2, virtual=True)
    compare(reference, candidate)
    print(f"SIGKILL mid-run ({complete} runs complete in the node shards): snapshots correct; --resume under MPI: "
          f"equal to the reference")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gesweep", required=True)
    parser.add_argument("--mpirun", default="mpirun")
    parser.add_argument("--runner", choices=("driver", "cli"), default="driver")
    parser.add_argument("--driver")
    parser.add_argument("--interrupt-after-s", type=float, default=1.0)
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
            check_killed(args, INTERRUPT_STUDY, work)
    except (Failure, subprocess.TimeoutExpired) as e:
        print(f"FAIL: {e}", file=sys.stderr)
        return 1
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
