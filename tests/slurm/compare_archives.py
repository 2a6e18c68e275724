#!/usr/bin/python3
"""Compares two gesweep archives run by run, bit for bit, provenance excluded.

  compare_archives.py REFERENCE.h5 CANDIDATE.h5

Used by scripts/slurm/selftest to check that a sweep run as a Slurm job array and merged equals the
same study run in one process (the determinism promise of docs/sweep.md: same study, same result
for every run whatever the thread count or sharding).

What must be equal: the set of groups and datasets; every dataset's dtype, shape and bytes (NaN
payloads included, so "bit for bit" means it); every attribute of every dataset and group, except
the provenance (schemas/archive.md): the root attributes that describe how and where the archive was
made (PROVENANCE_ROOT_ATTRIBUTES: host, threads, command lines, paths, times, merge inputs) and
anything under a `provenance` group.
A difference in a per-run dataset is reported with the first design indices that differ.
Exit 0 equal, 1 different, 2 bad usage.
"""

import sys

import h5py
import numpy as np

# Root attributes that describe one process's making of the archive, not its content
# (schemas/archive.md, "Provenance"): they legitimately differ between a single-process run and a
# merge of shards run elsewhere, at other times, with other thread counts and paths. Every other
# root attribute (the study and aircraft text and fingerprint, the engine version, commit and
# compiler, the design's run count, shard 0/1, the ok/failed/pending counts) must match. The batch
# size (chunk_runs) is how the archive was cut into chunks, not what it holds: an N-way split of a
# small design has smaller batches (ShardBatchRuns), and the datasets must still be equal.
PROVENANCE_ROOT_ATTRIBUTES = {
    "host", "threads", "command_line", "start_time", "end_time", "resumed_at",
    "study_path", "aircraft_path",  # as given on each command line
    "merged_from", "merged_shards", "merge_command_line", "merge_time",  # written by gesweep merge
    "merge_kind", "virtual_sources", "virtual_note",  # how the merge was made (virtual or copied)
    "archive_id", "merged_from_ids",  # each archive's own identity (schemas/archive.md, "Identity")
    "virtual_source_ids", "virtual_source_fingerprints", "virtual_source_first_runs",  # a virtual
    "virtual_source_run_counts", "virtual_source_shards",  # merge's record of the files it maps
    "chunk_runs", "mpi_ranks", "node_index", "node_count",  # how the runs were batched and spread
}

MAX_REPORTED_RUNS = 5


def provenance_root(name):
    return name in PROVENANCE_ROOT_ATTRIBUTES


def is_provenance_path(path):
    return "provenance" in path.strip("/").split("/")


def collect(archive):
    """{path: object} of every group and dataset below the root."""
    items = {}
    archive.visititems(lambda name, obj: items.__setitem__("/" + name, obj))
    return items


def attribute_bytes(value):
    array = np.asarray(value)
    return array.dtype.str, array.shape, array.tobytes() if array.dtype != object else repr(value).encode()


def referenced(obj, value):
    """The dimension scale attributes (schemas/archive.md, "netCDF view") with each object reference
    replaced by the path it refers to."""
    if isinstance(value, h5py.Reference):
        return obj.file[value].name if value else None
    if isinstance(value, np.void):
        value = value.tolist()
    if isinstance(value, (np.ndarray, list, tuple)):
        return tuple(referenced(obj, v) for v in value)
    return repr(value)


def compare_attributes(path, reference, candidate, problems, is_root=False):
    names = set(reference.attrs) | set(candidate.attrs)
    for name in sorted(names):
        if is_root and provenance_root(name):
            continue
        if name not in reference.attrs or name not in candidate.attrs:
            problems.append(f"{path}: attribute {name} only in "
                            f"{'reference' if name in reference.attrs else 'candidate'}")
            continue
        if name in ("DIMENSION_LIST", "REFERENCE_LIST"):  # object references: compare the paths they name
            # (a scale's list in any order: a merge attaches in path order, a sweep in layout order)
            order = sorted if name == "REFERENCE_LIST" else tuple
            if order(referenced(reference, reference.attrs[name])) != order(
                    referenced(candidate, candidate.attrs[name])):
                problems.append(f"{path}: attribute {name} refers to other objects")
            continue
        if attribute_bytes(reference.attrs[name]) != attribute_bytes(candidate.attrs[name]):
            problems.append(f"{path}: attribute {name} differs: {reference.attrs[name]!r} vs "
                            f"{candidate.attrs[name]!r}")


def run_labels(archive, count):
    """The design index of each row when the archive has one (for messages), else the row number."""
    for path in ("/runs/design_index", "/runs/index", "/runs/run_index"):
        if path in archive and archive[path].shape == (count,):
            return archive[path][()]
    return np.arange(count)


def compare_dataset(path, reference, candidate, problems, labels):
    if reference.dtype != candidate.dtype:
        problems.append(f"{path}: dtype {reference.dtype} vs {candidate.dtype}")
        return
    if reference.shape != candidate.shape:
        problems.append(f"{path}: shape {reference.shape} vs {candidate.shape}")
        return
    a = reference[()]
    b = candidate[()]
    if np.asarray(a).tobytes() == np.asarray(b).tobytes():
        return
    if a.ndim == 0 or labels is None or a.shape[0] != len(labels):
        problems.append(f"{path}: values differ")
        return
    rows = [i for i in range(a.shape[0]) if np.asarray(a[i]).tobytes() != np.asarray(b[i]).tobytes()]
    shown = ", ".join(f"run {labels[i]}: {a[i]!r} vs {b[i]!r}" for i in rows[:MAX_REPORTED_RUNS])
    problems.append(f"{path}: {len(rows)} of {a.shape[0]} runs differ ({shown}"
                    f"{', ...' if len(rows) > MAX_REPORTED_RUNS else ''})")


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    problems = []
    with h5py.File(argv[1], "r") as reference, h5py.File(argv[2], "r") as candidate:
        compare_attributes("/", reference, candidate, problems, is_root=True)
        ours = {p: o for p, o in collect(reference).items() if not is_provenance_path(p)}
        theirs = {p: o for p, o in collect(candidate).items() if not is_provenance_path(p)}
        for path in sorted(set(ours) ^ set(theirs)):
            problems.append(f"{path}: only in {'reference' if path in ours else 'candidate'}")
        runs = None
        for path in ("/runs/status",):
            if path in reference:
                runs = reference[path].shape[0]
        labels = run_labels(reference, runs) if runs is not None else None
        compared = 0
        for path in sorted(set(ours) & set(theirs)):
            a, b = ours[path], theirs[path]
            if isinstance(a, h5py.Dataset) != isinstance(b, h5py.Dataset):
                problems.append(f"{path}: a dataset in one archive, a group in the other")
                continue
            compare_attributes(path, a, b, problems)
            if isinstance(a, h5py.Dataset):
                compare_dataset(path, a, b, problems, labels)
                compared += 1
    if problems:
        print(f"compare_archives: {argv[2]} differs from {argv[1]}:", file=sys.stderr)
        for problem in problems:
            print(f"  {problem}", file=sys.stderr)
        return 1
    print(f"compare_archives: equal ({compared} datasets, {runs if runs is not None else '?'} runs; "
          "provenance excluded)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
