#!/usr/bin/python3
"""A sweep whose disk fills (issue 13, docs/reliability.md "Failing I/O").

    /usr/bin/python3 tests/reliability/disk_full.py GESWEEP

Two ways to run out of space, the second when it can be had:
- a file-size limit (RLIMIT_FSIZE, with SIGXFSZ ignored, so that write() fails with EFBIG): works
  everywhere, as any user;
- a real full disk: a 24 MB tmpfs (ENOSPC, "no space left on device"), as root when mount works
  (CI runs as root); otherwise SKIPPED with the reason.
Each time the sweep must exit 1 with ONE stderr line naming the archive and the cause, saying the
complete runs are kept and how to go on (--resume); the archive must hold only runs equal to an
uninterrupted sweep's (when the failed write left the file shorter than HDF5 recorded, as the
file-size limit does, gesweep's readers must say so with one line, exit 2); a --resume while the
disk is still full must refuse without changing it; once space is back, --resume must finish it,
equal run for run to the uninterrupted one."""
import os
import pathlib
import resource
import signal
import subprocess
import sys
import tempfile

import h5py
import numpy as np

GESWEEP = os.path.abspath(sys.argv[1])
ROOT = pathlib.Path(__file__).resolve().parents[2]
ANCE = ROOT / "studies" / "aircraft" / "ance.toml"
RUNS = 400000  # about 100 MB uncompressed: fills a 24 MB disk and a 20 MB file-size limit half-way
FILE_SIZE_LIMIT = 20 << 20
TMPFS_SIZE = "24M"

STUDY = f'''format_version = 1
name = "disk_full"
aircraft = "{ANCE}"
[analyses.modes]
[parameters]
speed_mps = 32.0208
[output]
chunk_runs = 1024
compression_level = 0
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
linspace = [1.0, 10.0, {RUNS}]
'''
failures = []


def run(args, preexec=None):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=600, preexec_fn=preexec)


def compare(archive, reference, require_complete):
    """Every complete run of `archive` equals the reference's; all complete when required."""
    with h5py.File(archive, "r", swmr=True) as f, h5py.File(reference, "r") as g:
        status = f["runs/status"][...]
        done = status != 0
        if require_complete and not done.all():
            failures.append(f"{archive}: {int((~done).sum())} runs still pending")
        columns = []
        g.visititems(lambda name, obj: columns.append(name) if isinstance(obj, h5py.Dataset) and
                     name.split("/")[0] in ("runs", "design", "results") else None)
        for column in columns:
            ours, theirs = f[column][...][done], g[column][...][done]
            same = np.array_equal(ours, theirs) if ours.dtype.kind in "SOV" else \
                np.array_equal(ours, theirs, equal_nan=True)
            if not same:
                failures.append(f"{archive}: {column} differs from the uninterrupted sweep")
        if not columns:
            failures.append(f"{reference}: no per-run dataset to compare")
        return int(done.sum())


def check_failure(name, result, archive, cause):
    lines = result.stderr.strip().splitlines()
    print(f"{name}: exit {result.returncode}: {result.stderr.strip()}")
    if result.returncode != 1:
        failures.append(f"{name}: exit {result.returncode}, expected 1")
    if len(lines) != 1:
        failures.append(f"{name}: {len(lines)} stderr lines, expected 1")
        return
    for fragment in (f"cannot write the archive {archive}", cause, "runs of complete batches are kept", "--resume"):
        if fragment not in lines[0]:
            failures.append(f"{name}: the line does not say {fragment!r}")


def file_size_limit():
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # inherited through exec: write() fails with EFBIG
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_SIZE_LIMIT, FILE_SIZE_LIMIT))


with tempfile.TemporaryDirectory() as tmp:
    tmp = pathlib.Path(tmp)
    study = tmp / "disk_full.toml"
    study.write_text(STUDY)
    reference = tmp / "reference.h5"
    result = run(["run", str(study), "-o", str(reference), "-q"])
    if result.returncode != 0:
        sys.exit(f"the reference sweep failed: {result.stderr}")

    # 1. A file-size limit.
    archive = tmp / "limited.h5"
    result = run(["run", str(study), "-o", str(archive), "-q"], preexec=file_size_limit)
    check_failure("file-size limit", result, archive, "file too large")
    # A write cut by the limit leaves the file shorter than HDF5 recorded: h5py and gesweep's readers
    # refuse it (gesweep saying so, exit 2); --resume extends it and copies its complete batches.
    query = run(["query", str(archive), "--describe"])
    print(f"  query: exit {query.returncode}: {query.stderr.strip()}")
    if query.returncode != 2 or "shorter than HDF5 recorded" not in query.stderr:
        try:
            kept = compare(archive, reference, require_complete=False)
            print(f"  {kept} of {RUNS} runs kept")
        except OSError as error:
            failures.append(f"file-size limit: the archive opens neither in gesweep nor in h5py: {error}")
    result = run(["run", str(study), "-o", str(archive), "--resume", "-q"])
    if result.returncode != 0:
        failures.append(f"file-size limit: --resume: exit {result.returncode}: {result.stderr.strip()}")
    compare(archive, reference, require_complete=True)

    # 2. A full disk.
    mount = tmp / "small_disk"
    mount.mkdir()
    mounted = False
    if os.geteuid() == 0:
        mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={TMPFS_SIZE}", "tmpfs", str(mount)],
                                 capture_output=True).returncode == 0
    if not mounted:
        print("SKIP the full-disk case: mounting a tmpfs needs root (and a mount namespace that allows it); "
              "the file-size limit above fails the same write path with EFBIG")
    else:
        try:
            archive = mount / "full.h5"
            result = run(["run", str(study), "-o", str(archive), "-q"])
            check_failure("full disk", result, archive, "no space left on device")
            kept = compare(archive, reference, require_complete=False)
            print(f"  {kept} of {RUNS} runs kept")
            before = archive.read_bytes()
            result = run(["run", str(study), "-o", str(archive), "--resume", "-q"])
            print(f"--resume on the full disk: exit {result.returncode}: {result.stderr.strip()}")
            if result.returncode != 1 or "not enough space" not in result.stderr:
                failures.append(f"--resume on the full disk: exit {result.returncode}: {result.stderr.strip()}")
            if archive.read_bytes() != before:
                failures.append("--resume on the full disk changed the archive")
            subprocess.run(["mount", "-o", "remount,size=400M", str(mount)], check=True)
            result = run(["run", str(study), "-o", str(archive), "--resume", "-q"])
            if result.returncode != 0:
                failures.append(f"full disk: --resume with space: exit {result.returncode}: {result.stderr.strip()}")
            compare(archive, reference, require_complete=True)
        finally:
            subprocess.run(["umount", str(mount)], capture_output=True)

for failure in failures:
    print("FAIL", failure)
sys.exit(1 if failures else 0)
