"""The one reader of archive files in Python: gesweep.open_archive and scripts/report both open archives
here, and only after the engine has checked them (docs/python.md, docs/report.md, "One reader").

Pure Python over h5py: it imports nothing of the native module, so that scripts/report, which runs
beside a gesweep binary and not always beside the module, loads this file as it is (load_shared in
scripts/report/report_data.py). What the engine's check says of an archive (gesweep check --format json,
or the module's _check_archive: the same ArchiveReader::Open) is the only validation: nothing here
re-derives the layout or mirrors a check of the engine.
"""

import h5py
import numpy as np

# The kinds of HDF5 object an archive holds (schemas/archive.md): for isinstance, so that a reader of
# archives names h5py nowhere else.
Dataset, Group = h5py.Dataset, h5py.Group

# What `gesweep check` and the module's check call a sweep's archive and a subset-simulation archive.
KIND_RUNS, KIND_SUBSET = "runs", "subset_simulation"

# HDF5 dimension-scale bookkeeping attributes (not the archive's own).
_BOOKKEEPING = ("DIMENSION_LIST", "REFERENCE_LIST", "CLASS", "NAME", "_Netcdf4Dimid", "_Netcdf4Coordinates")


def open_checked(path, checked):
    """The archive at `path`, read-only, as the engine's check `checked` found it: a snapshot (a sweep
    is writing it, or its writer died) opened in SWMR-read mode, so that what is read is what was
    complete when the statuses were read. `checked` is one entry of `gesweep check --format json` or the
    dict of the module's _check_archive; OSError when the file changed between the check and the open."""
    return h5py.File(path, "r", swmr=bool(checked.get("snapshot", False)))


def text(value):
    """An attribute as Python text: bytes decoded, arrays of text as lists of str; numbers as stored."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray):
        return [text(v) for v in value.tolist()]
    if isinstance(value, (list, tuple)):
        return [text(v) for v in value]
    return value


def attrs(obj):
    """The attributes of a dataset or group as Python values (text decoded), without HDF5's
    dimension-scale bookkeeping."""
    out = {}
    for key, value in obj.attrs.items():
        if key in _BOOKKEEPING:
            continue
        value = text(value)
        if isinstance(value, np.ndarray) and value.size == 1:
            value = value.item()
        out[key] = value
    return out


def is_dataset(obj):
    return isinstance(obj, Dataset)


def is_group(obj):
    return isinstance(obj, Group)
