"""What the report needs of archives beyond reading them (docs/report.md, "One reader").

Every archive is first checked by the engine (`gesweep check --format json`: ArchiveReader::Open, or
`gesweep risk`'s reader for a subset-simulation archive), the one validator; it says what the file is and
whether it is a snapshot. It is then opened and read by the module that gesweep.open_archive reads
archives with (engine/python/gesweep/_hdf5.py: SweepArchive and RiskArchive, every path from the column
manifest's layout), read-only; a snapshot in SWMR-read mode, and only complete runs (status ok or
failed) are used: a nonzero status is written after the run's values (docs/sweep.md, "Crash safety"),
and statuses are read before values. What is left here is the report's own: the aircraft's facts from
the stored aircraft file, the groups of runs along the other axes, their labels in words, and which
archives are dispersion studies.
"""

import importlib.util
import json
import math
import os
import subprocess
import sys
import tomllib

import numpy as np

_LIB = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "lib")
if _LIB not in sys.path:
    sys.path.insert(0, _LIB)
import columns  # noqa: E402  (scripts/lib/columns.py: archive paths from `gesweep columns --json`)
import report_labels  # noqa: E402  (the one labeller of parameter values)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The Python package's reader of archive files, loaded as a file: the report runs beside a gesweep
# binary, not always beside a built module (the sanitized build has none), and the file imports
# nothing of the module's native part.
SHARED_READER = os.path.join(ROOT, "engine", "python", "gesweep", "_hdf5.py")


def load_shared(path=SHARED_READER):
    spec = importlib.util.spec_from_file_location("gesweep_hdf5", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


hdf5 = load_shared()
# `gesweep check` runs in a few milliseconds per archive; a damaged one is given GESWEEP_ARCHIVE_CHECK_S.
CHECK_TIMEOUT_S = 600


class Aircraft:
    """What the report needs of the aircraft file stored in the archive (attribute aircraft_text)."""

    def __init__(self, text):
        data = tomllib.loads(text) if text else {}
        self.name = data.get("name", "")
        self.wingspan_m = data.get("geometry", {}).get("wingspan_m", math.nan)
        limits = data.get("limits", {})
        self.wheel_contact_height_m = limits.get("wheel_contact_height_m", math.nan)
        self.stall_speed_mps = limits.get("stall_speed_mps", math.nan)
        table = data.get("table", {})
        self.table_heights_m = list(table.get("height_m", []))
        # Coefficient columns of the finite rows, by name (CMalphadot, ...), as in the aircraft file.
        self.table = {name: list(values) for name, values in table.items()
                      if name != "height_m" and isinstance(values, list) and len(values) == len(self.table_heights_m)}


def layout():
    """The archive layout of the column manifest (the gesweep that runs the report)."""
    return hdf5.Layout(columns.manifest())


def check(paths):
    """What the engine's check says of each archive (`gesweep check --format json`: a list of {path,
    kind, snapshot, virtual, notes}, in the order given), or ValueError with its one line (the first
    archive it refuses)."""
    gesweep = columns.gesweep_binary()
    try:
        out = subprocess.run([gesweep, "check", "--format", "json", "--", *paths], capture_output=True,
                             text=True, timeout=CHECK_TIMEOUT_S)
    except (OSError, subprocess.SubprocessError) as error:
        raise ValueError(f"{gesweep}: cannot run `gesweep check` on the archives ({error}); build it "
                         f"(cmake --build build) or set {columns.BINARY_ENV} to a gesweep binary") from None
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or [f"gesweep check failed (exit {out.returncode})"])[-1]
        raise ValueError(last.removeprefix("gesweep: error: "))
    checked = json.loads(out.stdout)
    if [c["path"] for c in checked] != list(paths):
        raise ValueError(f"{gesweep}: `gesweep check` answered for other archives than were asked")
    return checked


class Archive(hdf5.SweepArchive):
    """A sweep's archive as the shared reader reads it, with what the report adds: the aircraft, the
    study's name, the groups of runs along the other axes and their labels, and whether it is a
    dispersion study."""

    def __init__(self, path, checked):
        super().__init__(path, checked, layout())
        self.aircraft = Aircraft(self.attrs.get("aircraft_text", ""))
        self.study_name = self.attrs.get("study_name", path)

    def other_axes(self, exclude):
        """Design parameters besides `exclude`."""
        return [n for n in self.design_names if n not in exclude]

    def groups(self, exclude):
        """Complete runs grouped by the values of the design parameters other than `exclude`:
        a list of (key dict, run indices), in key order. (A pending run's design values may be
        fill values, NaN.)"""
        axes = self.other_axes(exclude)
        complete = np.nonzero(self.complete)[0]
        if not axes:
            return [({}, complete)]
        values = np.stack([self.param(a)[complete] for a in axes], axis=1)
        keys, inverse = np.unique(values, axis=0, return_inverse=True)
        inverse = np.asarray(inverse).reshape(-1)
        order = np.argsort(inverse, kind="stable")
        members = np.split(complete[order], np.cumsum(np.bincount(inverse, minlength=len(keys)))[:-1])
        return [({a: float(k[i]) for i, a in enumerate(axes)}, m) for k, m in zip(keys, members)]

    def key_text(self, key):
        """A group's key in words (report_labels: "W20 = 30 kt headwind, with h-derivatives")."""
        return report_labels.key_label(key, self.design_levels)

    def value_text(self, name, value):
        """One parameter value in words (report_labels.value_label with the archive's levels)."""
        return report_labels.value_label(name, value, self.design_levels(name))

    def design_levels(self, name):
        """The level names of a choice or boolean parameter as the archive stores them, or None (then
        the labeller takes the manifest's)."""
        return self.levels(self.layout.design_path(name)) or None

    def is_dispersion(self):
        """Whether the archive is a dispersion study: it has /analysis/dispersion, or its runs fly in
        turbulence. Such an archive is shown in its own section only (docs/report.md)."""
        if "dispersion" in self.products():
            return True
        turbulence = self.param("turbulence")
        if turbulence is None:
            return False
        levels = self.design_levels("turbulence") or report_labels.parameter("turbulence")["levels"]
        return any(levels[int(v)] != "none" for v in np.unique(turbulence[self.complete]) if np.isfinite(v))


class RiskArchive(hdf5.RiskArchive):
    """A subset-simulation archive as the shared reader reads it, with the study's name (no aircraft)."""

    def __init__(self, path, checked):
        super().__init__(path, checked, layout())
        self.study_name = self.result.get("study", path)
        self.aircraft = Aircraft("")


def open_archives(paths):
    """Checks every archive (the engine's check, `check`) and opens them all before anything is drawn;
    ValueError (one line) for a bad one."""
    archives = []
    try:
        for checked in check(list(paths)):
            kind = checked["kind"]
            if kind not in (hdf5.KIND_RUNS, hdf5.KIND_SUBSET):
                raise ValueError(f"{checked['path']}: an archive of a kind this report does not read ({kind})")
            archives.append((RiskArchive if kind == hdf5.KIND_SUBSET else Archive)(checked["path"], checked))
    except (KeyError, TypeError, hdf5.LayoutError) as error:  # a layout the report cannot read as it expects
        for archive in archives:
            archive.close()
        raise ValueError(f"{checked['path']}: cannot read it as a gesweep archive ({error})") from None
    except (OSError, ValueError):
        for archive in archives:
            archive.close()
        raise
    return archives
