"""Shared logic of scripts/slurm/{submit,resubmit,status}: run a gesweep study as a Slurm job array.

The plan of a submission lives in OUT_DIR/slurm-sweep.json (the manifest): the study and its SHA-256,
the gesweep binary, the run count, the shard count N, the Slurm options and every job submitted for
it. Shard i (0 <= i < N) is written by array task i to OUT_DIR/shard-<i>.h5 with
`gesweep run STUDY -o OUT_DIR/shard-<i>.h5 --shard i/N --resume --threads T`; the merge job writes
OUT_DIR/merged.h5 with `gesweep merge`. docs/cluster.md explains the workflow.

Standard library only (Python >= 3.9): cluster login nodes rarely have numpy or h5py.
"""

import hashlib
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys

SCRIPTS_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REPO_ROOT = os.path.dirname(os.path.dirname(SCRIPTS_DIR))
MANIFEST_NAME = "slurm-sweep.json"
MANIFEST_FORMAT = "gesweep-slurm/1"
MERGED_NAME = "merged.h5"

# Without --tasks, each task gets about this much work (single-thread seconds from the dry run's
# time estimate, divided by the task's threads): long enough that scheduling overhead (seconds) is
# noise, short enough that a requeue loses little.
DEFAULT_TASK_SECONDS = 3600.0
# Slurm's default MaxArraySize (task ids 0..1000) when the cluster cannot be asked.
DEFAULT_MAX_ARRAY_SIZE = 1001


class UsageError(Exception):
    """A bad argument or an inconsistent OUT_DIR: printed as one line, exit code 2."""


def fail(prog, message, code=2):
    print(f"{prog}: error: {message}", file=sys.stderr)
    sys.exit(code)


def script_path(name):
    """How to call scripts/slurm/<name> from here: relative when below the current directory."""
    path = os.path.join(SCRIPTS_DIR, name)
    relative = os.path.relpath(path)
    return relative if not relative.startswith("..") else path


def shard_path(out_dir, index):
    return os.path.join(out_dir, f"shard-{index}.h5")


def sha256_of(path):
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def find_gesweep(explicit):
    """The gesweep binary: --gesweep, else $GESWEEP, else `gesweep` on PATH, else build/gesweep."""
    candidates = [explicit, os.environ.get("GESWEEP"), shutil.which("gesweep"),
                  os.path.join(REPO_ROOT, "build", "gesweep")]
    for candidate in candidates:
        if candidate and os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return os.path.abspath(candidate)
    raise UsageError("no gesweep binary: pass --gesweep PATH, set GESWEEP, put gesweep on PATH, "
                     "or build it (./scripts/test builds build/gesweep)")


def parse_shard_list(text, shards):
    """'1,4-6' -> [1, 4, 5, 6]; every index must be in [0, shards)."""
    indices = set()
    for part in text.split(","):
        part = part.strip()
        match = re.fullmatch(r"(\d+)(?:-(\d+))?", part)
        if not match:
            raise UsageError(f"shard list '{text}': expected indices like 1,4-6")
        first = int(match.group(1))
        last = int(match.group(2)) if match.group(2) else first
        if last < first or last >= shards:
            raise UsageError(f"shard list '{text}': indices must lie in 0..{shards - 1}")
        indices.update(range(first, last + 1))
    return sorted(indices)


def format_shard_list(indices):
    """[1, 4, 5, 6] -> '1,4-6' (Slurm's --array syntax)."""
    parts = []
    start = previous = None
    for index in sorted(indices):
        if start is None:
            start = previous = index
        elif index == previous + 1:
            previous = index
        else:
            parts.append(f"{start}" if start == previous else f"{start}-{previous}")
            start = previous = index
    if start is not None:
        parts.append(f"{start}" if start == previous else f"{start}-{previous}")
    return ",".join(parts)


# ---------------------------------------------------------------------------------------------
# gesweep run --dry-run


def dry_run(gesweep, study, archive):
    """Runs `gesweep run STUDY -o ARCHIVE --dry-run --format json --threads 1` and returns its JSON.

    Uses its `design_runs` (the run count of the whole design) and `seconds_per_run` (measured on
    a few sample runs, one thread). A bad study is the user's error: gesweep's own one-line message
    is passed on (exit 2).
    """
    command = [gesweep, "run", study, "-o", archive, "--dry-run", "--format", "json", "--threads", "1"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        message = result.stderr.strip() or result.stdout.strip()
        raise UsageError(message.removeprefix("gesweep: error: ") if result.returncode == 2 else
                         f"`{shlex.join(command)}` failed (exit {result.returncode}): {message}")
    try:
        report = json.loads(result.stdout)
    except json.JSONDecodeError as error:
        raise UsageError(f"`{shlex.join(command)}` did not print JSON ({error}): {result.stdout[:200]!r}")
    if not isinstance(report.get("design_runs"), int) or report["design_runs"] < 0:
        raise UsageError(f"`{shlex.join(command)}` printed no integer 'design_runs': {result.stdout[:200]!r}")
    return report


def choose_shard_count(runs, tasks, threads, estimate_s, max_array_size):
    """The number of array tasks N.

    --tasks wins (capped at the run count, so no shard is empty); otherwise the dry run's
    single-thread time estimate is cut into tasks of about DEFAULT_TASK_SECONDS of wall time.
    Always 1 <= N <= min(runs, max_array_size), with N = 1 for an empty study.
    """
    if tasks is not None:
        wanted = tasks
    elif estimate_s is not None and estimate_s > 0:
        wanted = math.ceil(estimate_s / (threads * DEFAULT_TASK_SECONDS))
    else:
        wanted = 1
    return max(1, min(wanted, runs, max_array_size))


# ---------------------------------------------------------------------------------------------
# Slurm


def run_slurm(command):
    """Runs a Slurm client command; returns stdout. A failure is reported with Slurm's message."""
    try:
        result = subprocess.run(command, capture_output=True, text=True)
    except FileNotFoundError:
        raise UsageError(f"`{command[0]}` not found: run this on a Slurm login node "
                         "(or pass --dry-run to print the commands)")
    if result.returncode != 0:
        message = "; ".join(line.strip() for line in (result.stderr or result.stdout).splitlines() if line.strip())
        raise UsageError(f"`{command[0]} {command[1]}` failed (exit {result.returncode}): {message}")
    return result.stdout


def sbatch(arguments, dry):
    """Submits with `sbatch --parsable ...` and returns the job id (a placeholder when dry)."""
    command = ["sbatch", "--parsable", *arguments]
    if dry:
        print(shlex.join(command))
        return "<job-id>"
    output = run_slurm(command).strip()
    job_id = output.split(";")[0]
    if not job_id.isdigit():
        raise UsageError(f"sbatch printed no job id: {output!r}")
    return job_id


def max_array_size():
    """The cluster's MaxArraySize (task ids must stay below it), or Slurm's default."""
    try:
        output = subprocess.run(["scontrol", "show", "config"], capture_output=True, text=True,
                                timeout=30).stdout
    except (OSError, subprocess.TimeoutExpired):
        return DEFAULT_MAX_ARRAY_SIZE
    match = re.search(r"^MaxArraySize\s*=\s*(\d+)", output, re.MULTILINE)
    return int(match.group(1)) if match else DEFAULT_MAX_ARRAY_SIZE


def queued_states(job_ids):
    """{(job_id, task_index or None): state} for the given jobs still known to squeue."""
    states = {}
    if not job_ids:
        return states
    command = ["squeue", "-h", "-r", "-j", ",".join(job_ids), "-o", "%F %K %T"]
    try:
        result = subprocess.run(command, capture_output=True, text=True)
    except FileNotFoundError:
        raise UsageError("`squeue` not found: run this on a Slurm login node")
    if result.returncode != 0:
        if "Invalid job id" not in result.stderr:
            # Never guess that a task has ended: a rerun beside a live task would corrupt its shard.
            raise UsageError(f"`{shlex.join(command)}` failed: {result.stderr.strip()}")
        # squeue rejects the whole list when one id is unknown (purged long ago): ask one by one.
        if len(job_ids) > 1:
            for job_id in job_ids:
                states.update(queued_states([job_id]))
        return states
    for line in result.stdout.splitlines():
        fields = line.split()
        if len(fields) != 3:
            continue
        job_id, task, state = fields
        states[(job_id, int(task) if task.isdigit() else None)] = state
    return states


ACTIVE_STATES = {"PENDING", "RUNNING", "CONFIGURING", "COMPLETING", "REQUEUED", "RESIZING",
                 "SUSPENDED", "REQUEUE_HOLD", "REQUEUE_FED", "SIGNALING", "STAGE_OUT"}


def array_sbatch_arguments(manifest, indices, options):
    """sbatch arguments of a job array of shard_task over the shard `indices`."""
    out_dir = manifest["out_dir"]
    return [f"--array={format_shard_list(indices)}",
            f"--job-name=gesweep:{manifest['name']}",
            f"--cpus-per-task={manifest['threads_per_task']}",
            "--ntasks=1", "--nodes=1",
            # Requeue-safe: Slurm may requeue a task; its log is appended to, not truncated.
            "--requeue", "--open-mode=append",
            f"--output={os.path.join(out_dir, 'logs', 'shard-%a.log')}",
            *options,
            os.path.join(SCRIPTS_DIR, "shard_task"),
            manifest["gesweep"], manifest["study"], manifest["study_sha256"], out_dir,
            str(manifest["shards"]), str(manifest["threads_per_task"])]


def merge_sbatch_arguments(manifest, dependency, options):
    """sbatch arguments of the merge job; `dependency` may be empty (run now)."""
    out_dir = manifest["out_dir"]
    # Stay pending if a task fails, so scripts/slurm/resubmit can re-point this job at the rerun
    # tasks instead of it being cancelled.
    waiting = [f"--dependency={dependency}", "--kill-on-invalid-dep=no"] if dependency else []
    return [*waiting,
            f"--job-name=gesweep:{manifest['name']}:merge",
            "--cpus-per-task=1", "--ntasks=1", "--nodes=1",
            "--open-mode=append",
            f"--output={os.path.join(out_dir, 'logs', 'merge.log')}",
            *options,
            os.path.join(SCRIPTS_DIR, "merge_job"),
            SCRIPTS_DIR, manifest["gesweep"], out_dir, str(manifest["shards"]), manifest.get("merge", "virtual")]


# ---------------------------------------------------------------------------------------------
# The manifest


def manifest_path(out_dir):
    return os.path.join(out_dir, MANIFEST_NAME)


def read_manifest(out_dir):
    path = manifest_path(out_dir)
    try:
        with open(path) as handle:
            manifest = json.load(handle)
    except FileNotFoundError:
        raise UsageError(f"{path} not found: OUT_DIR was not made by scripts/slurm/submit")
    except json.JSONDecodeError as error:
        raise UsageError(f"{path} is not valid JSON: {error}")
    if manifest.get("format") != MANIFEST_FORMAT:
        raise UsageError(f"{path}: format {manifest.get('format')!r}, expected {MANIFEST_FORMAT!r}")
    return manifest


def write_manifest(out_dir, manifest):
    """Writes the manifest atomically (a reader never sees half of it)."""
    path = manifest_path(out_dir)
    temporary = path + ".tmp"
    with open(temporary, "w") as handle:
        json.dump(manifest, handle, indent=2)
        handle.write("\n")
    os.replace(temporary, path)


def check_study_unchanged(manifest):
    """Shards of one sweep must come from one study text: refuse if the study file changed."""
    study = manifest["study"]
    if not os.path.isfile(study):
        raise UsageError(f"the study {study} named in the manifest no longer exists")
    if sha256_of(study) != manifest["study_sha256"]:
        raise UsageError(f"the study {study} changed since it was submitted (SHA-256 differs): "
                         "its shards would not merge; restore it or submit to a new OUT_DIR")


# ---------------------------------------------------------------------------------------------
# Shard completeness


def shard_progress(manifest, index):
    """(state, detail) of shard `index`: 'complete', 'incomplete', 'missing', or 'present' (exists;
    its runs not counted because h5py is not available).

    Reads the shard archive (schemas/archive.md): it must be a gesweep archive of shard i/N of a
    design of the manifest's run count, readable without SWMR (a file a sweep is still writing, or
    whose writer was killed, is not complete), with no run whose runs/status is 0 (pending).
    Needs h5py; without it only the archive's presence is checked and `gesweep merge`, which makes
    the same checks, has the last word.
    """
    archive = shard_path(manifest["out_dir"], index)
    if not os.path.lexists(archive):
        return "missing", "no archive"
    if not os.path.isfile(archive):
        return "incomplete", "not a file"
    try:
        import h5py
    except ImportError:
        return "present", "h5py not available to count its runs; gesweep merge will check them"
    shards = manifest["shards"]
    try:
        handle = h5py.File(archive, "r")
        snapshot = False
    except OSError:
        try:
            handle = h5py.File(archive, "r", swmr=True)
            snapshot = True
        except OSError as error:
            return "incomplete", f"unreadable: {error}"
    with handle:
        attributes = handle.attrs
        shard = attributes.get("shard")
        shard = shard.decode() if isinstance(shard, bytes) else shard
        if attributes.get("format") not in ("gesweep-archive", b"gesweep-archive"):
            return "incomplete", "not a gesweep archive"
        if shard != f"{index}/{shards}" or int(attributes.get("design_runs", -1)) != manifest["runs"]:
            return "incomplete", (f"wrong archive: shard {shard} of {attributes.get('design_runs')} runs, "
                                  f"expected {index}/{shards} of {manifest['runs']}")
        # The shard's own run count: gesweep cuts shards at batch boundaries (engine/sweep/sweep_plan.h,
        # ShardRange); `gesweep merge` checks that the shards cover the design exactly once.
        expected_count = int(attributes.get("run_count", -1))
        if "runs/status" not in handle or handle["runs/status"].shape != (expected_count,):
            return "incomplete", "no runs/status of the shard's length"
        status = handle["runs/status"][()]
    pending = int((status == 0).sum())
    done = expected_count - pending
    if snapshot:
        return "incomplete", (f"{done} of {expected_count} runs; still being written, or its writer "
                              "was killed")
    if pending:
        return "incomplete", f"{done} of {expected_count} runs"
    return "complete", f"{expected_count} runs"


def all_shard_progress(manifest):
    return [(index, *shard_progress(manifest, index)) for index in range(manifest["shards"])]


# Shard states that forbid a merge.
BLOCKING_STATES = ("missing", "incomplete")


def describe_incomplete(progress):
    """'1 (missing: no archive), 2 (incomplete: 40 of 100 runs)'."""
    return ", ".join(f"{index} ({state}: {detail})" for index, state, detail in progress
                     if state in BLOCKING_STATES)
