"""Helpers of the reliability tests: run gesweep, open an archive with h5py the way a user would
(normally, or as a SWMR snapshot when a sweep is writing it or died), and compare archives run by run,
byte for byte. Independent of the engine's own reader (engine/archive): h5py and numpy only.

The layout is schemas/archive.md: one row per run in every dataset under runs/, design/, results/ and
the 2-D ones under series/; root attributes are provenance (excluded from comparisons except the
counts that must agree with the statuses)."""
import os
import pathlib
import subprocess

import h5py
import numpy as np

# Root attributes that differ between two runs of the same study by design: who, where, when, how.
PROVENANCE_ATTRIBUTES = {
    "command_line", "host", "threads", "start_time", "end_time", "resumed_at", "study_path", "aircraft_path",
    "merged_from", "archive_id",  # each archive's own identity (schemas/archive.md, "Identity")
}
PER_RUN_GROUPS = ("runs/", "design/", "results/", "series/")
STATUS = "runs/status"
INDEX = "runs/index"
RUN_ID = "runs/id"


class ArchiveProblem(Exception):
    """An archive that is wrong: missing, duplicated or different runs, garbage, unreadable."""


def gesweep(binary, args, timeout=120, **kwargs):
    """Runs gesweep to completion; returns the CompletedProcess (text output)."""
    return subprocess.run([binary, *args], capture_output=True, text=True, timeout=timeout, **kwargs)


def start_gesweep(binary, args, stderr_path):
    """Starts gesweep in the background; stderr goes to `stderr_path`."""
    with open(stderr_path, "wb") as err:
        return subprocess.Popen([binary, *args], stdout=subprocess.DEVNULL, stderr=err)


def has_subcommand(binary, name):
    """Whether this gesweep build has subcommand `name` (e.g. query, written in parallel)."""
    result = gesweep(binary, [name, "--help"], timeout=30)
    return result.returncode == 0


def open_archive(path):
    """Opens an archive read-only as a user would: normally, else (a sweep is writing it, or its
    writer died) as a SWMR snapshot. Returns (h5py.File, snapshot). Raises OSError when neither works."""
    try:
        return h5py.File(path, "r"), False
    except OSError:
        return h5py.File(path, "r", swmr=True), True


def dataset_paths(handle):
    paths = []
    handle.visititems(lambda name, obj: paths.append(name) if isinstance(obj, h5py.Dataset) else None)
    return sorted(paths)


def is_per_run(path, dataset, run_count):
    return path.startswith(PER_RUN_GROUPS) and dataset.ndim >= 1 and dataset.shape[0] == run_count and not (
        path.startswith("series/") and dataset.ndim == 1)


def row_bytes(dataset):
    """The dataset's rows as a (rows, bytes per row) uint8 array: compares NaNs, compounds and fixed
    strings exactly."""
    values = np.ascontiguousarray(dataset[()])
    rows = values.shape[0]
    return values.view(np.uint8).reshape(rows, -1) if rows else np.zeros((0, 0), np.uint8)


class Snapshot:
    """Everything of an archive a comparison needs, read in one go (the file is closed after)."""

    def __init__(self, path):
        handle, self.snapshot = open_archive(path)
        with handle:
            self.attributes = {k: _plain(v) for k, v in handle.attrs.items()}
            if self.attributes.get("format") != "gesweep-archive":
                raise ArchiveProblem(f"{path}: root attribute format = {self.attributes.get('format')!r}")
            self.run_count = int(self.attributes["run_count"])
            self.first_run = int(self.attributes["first_run"])
            # The statuses first: a sweep may be writing the file, and a run whose status is set when
            # it is read has its results on disk already (the writer flushes them before its status);
            # read after the columns, it could name runs whose columns were read before they were
            # written. Rows are judged complete by this one reading.
            self.rows = {STATUS: row_bytes(handle[STATUS])} if STATUS in handle else {}
            self.paths = dataset_paths(handle)
            self.shared = {}
            self.dataset_attributes = {}
            for name in self.paths:
                dataset = handle[name]
                self.dataset_attributes[name] = _attributes(handle, dataset)
                if name == STATUS:
                    continue
                if is_per_run(name, dataset, self.run_count):
                    self.rows[name] = row_bytes(dataset)
                else:
                    self.shared[name] = np.ascontiguousarray(dataset[()]).tobytes()
            self.group_attributes = {}
            handle.visititems(lambda name, obj: self.group_attributes.__setitem__(
                name, _attributes(handle, obj)) if isinstance(obj, h5py.Group) else None)
            for required in (STATUS, INDEX, RUN_ID):
                if required not in self.rows:
                    raise ArchiveProblem(f"{path}: no per-run dataset {required}")
            self.status = np.frombuffer(self.rows[STATUS].tobytes(), np.int8)
            self.index = np.frombuffer(self.rows[INDEX].tobytes(), "<i8")
            self.run_id = np.frombuffer(self.rows[RUN_ID].tobytes(), "<u8")

    def complete(self):
        """Rows whose run is complete (nonzero status)."""
        return np.nonzero(self.status != 0)[0]


def _attributes(handle, obj):
    """An object's attributes as plain values; the object references of the dimension scale attributes
    (schemas/archive.md, "netCDF view") as the paths they refer to."""
    return {k: _references(handle, v) if k in ("DIMENSION_LIST", "REFERENCE_LIST") else _plain(v)
            for k, v in obj.attrs.items()}


def _references(handle, value):
    if isinstance(value, h5py.Reference):
        return handle[value].name if value else None
    if isinstance(value, (np.ndarray, np.void, list, tuple)):
        return tuple(_references(handle, v) for v in (value.tolist() if isinstance(value, np.void) else value))
    return _plain(value)


# What a NaN attribute value compares as: NaN != NaN would make equal archives differ.
NAN = ("NaN",)


def _plain(value):
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray):
        return tuple(_plain(v) for v in value.tolist())
    if isinstance(value, (list, tuple)):
        return tuple(_plain(v) for v in value)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and value != value:
        return NAN  # a NaN setting (e.g. turbulence_sigma_w_mps: "0.1·|W20|") equals itself here
    return value


def check_consistent(archive, label):
    """Checks what any archive, complete or a snapshot, must satisfy: statuses are 0, 1 or 2; every
    complete run sits at its own row (index = first_run + row, so no run appears twice) with a
    unique id. Raises ArchiveProblem."""
    bad = np.setdiff1d(np.unique(archive.status), [0, 1, 2])
    if bad.size:
        raise ArchiveProblem(f"{label}: statuses {bad.tolist()} (expected 0, 1, 2)")
    rows = archive.complete()
    expected_index = archive.first_run + rows
    wrong = rows[archive.index[rows] != expected_index]
    if wrong.size:
        raise ArchiveProblem(f"{label}: {wrong.size} complete runs at the wrong row, e.g. row {wrong[0]} has index "
                             f"{archive.index[wrong[0]]}")
    ids = archive.run_id[rows]
    if np.unique(ids).size != ids.size:
        raise ArchiveProblem(f"{label}: duplicate run ids among the complete runs")


def compare_complete_rows(reference, archive, label):
    """Every complete run of `archive` equals the reference's run, byte for byte, in every dataset.
    Returns the number of complete runs. Raises ArchiveProblem."""
    check_consistent(archive, label)
    if archive.run_count != reference.run_count or archive.first_run != reference.first_run:
        raise ArchiveProblem(f"{label}: {archive.run_count} runs from {archive.first_run}, reference "
                             f"{reference.run_count} from {reference.first_run}")
    if set(archive.paths) != set(reference.paths):
        raise ArchiveProblem(f"{label}: datasets differ: only in archive "
                             f"{sorted(set(archive.paths) - set(reference.paths))[:5]}, only in reference "
                             f"{sorted(set(reference.paths) - set(archive.paths))[:5]}")
    rows = archive.complete()
    for path, values in reference.rows.items():
        got = archive.rows[path]
        if got.shape != values.shape:
            raise ArchiveProblem(f"{label}: {path} has shape {got.shape}, reference {values.shape}")
        differ = rows[np.any(got[rows] != values[rows], axis=1)]
        if differ.size:
            raise ArchiveProblem(f"{label}: {path}: {differ.size} complete runs differ from the reference, e.g. "
                                 f"run {archive.first_run + differ[0]}")
    for path, values in reference.shared.items():
        if archive.shared[path] != values:
            raise ArchiveProblem(f"{label}: {path} differs from the reference")
    return int(rows.size)


def compare_final(reference, archive, label):
    """A finished archive equals the reference: every run present once and complete, results equal
    bit for bit, dataset and group attributes equal, root attributes equal but for provenance, and
    the run counts agree with the statuses. Raises ArchiveProblem."""
    complete = compare_complete_rows(reference, archive, label)
    if complete != reference.run_count:
        missing = np.nonzero(archive.status == 0)[0]
        raise ArchiveProblem(f"{label}: {missing.size} runs missing (status pending), e.g. run "
                             f"{archive.first_run + missing[0]}")
    if not np.array_equal(archive.status, reference.status):
        raise ArchiveProblem(f"{label}: statuses differ from the reference")
    if archive.snapshot:
        raise ArchiveProblem(f"{label}: still opens only as a SWMR snapshot (not closed cleanly)")
    if archive.dataset_attributes != reference.dataset_attributes:
        raise ArchiveProblem(f"{label}: dataset attributes differ")
    if archive.group_attributes != reference.group_attributes:
        raise ArchiveProblem(f"{label}: group attributes differ")
    for key in set(reference.attributes) | set(archive.attributes):
        if key in PROVENANCE_ATTRIBUTES:
            continue
        if archive.attributes.get(key) != reference.attributes.get(key):
            raise ArchiveProblem(f"{label}: root attribute {key} = {archive.attributes.get(key)!r}, reference "
                                 f"{reference.attributes.get(key)!r}")
    counts = {"runs_ok": int(np.sum(archive.status == 1)), "runs_failed": int(np.sum(archive.status == 2)),
              "runs_pending": int(np.sum(archive.status == 0))}
    for key, value in counts.items():
        if int(archive.attributes.get(key, -1)) != value:
            raise ArchiveProblem(f"{label}: root attribute {key} = {archive.attributes.get(key)} but the statuses "
                                 f"give {value}")
    if int(archive.attributes.get("complete", 0)) != 1:
        raise ArchiveProblem(f"{label}: root attribute complete = {archive.attributes.get('complete')}")


def leftovers(directory, keep):
    """Files in `directory` other than `keep` (names)."""
    return sorted(p.name for p in pathlib.Path(directory).iterdir() if p.name not in keep)


def describe_stderr(path, limit=400):
    try:
        return pathlib.Path(path).read_text(errors="replace").strip()[-limit:]
    except OSError:
        return ""


def source_root():
    return pathlib.Path(__file__).resolve().parent.parent.parent


def environment_seed(name, default):
    value = os.environ.get(name)
    return int(value) if value else default
