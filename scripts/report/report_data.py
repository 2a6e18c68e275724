"""Reading gesweep archives for the report (layout: schemas/archive.md, docs/report.md, "One reader").

Every archive is first checked by the engine (`gesweep check --format json`: ArchiveReader::Open, or
`gesweep risk`'s reader for a subset-simulation archive), the one validator; it says what the file is and
whether it is a snapshot. It is then opened by the module that gesweep.open_archive opens archives with
(engine/python/gesweep/_hdf5.py), read-only; a snapshot (a sweep is writing it, or its writer was killed)
in SWMR-read mode, and only complete runs (status ok or failed) are used: a nonzero status is written
after the run's values (docs/sweep.md, "Crash safety"), and statuses are read before values.
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

STATUS_PENDING, STATUS_OK, STATUS_FAILED = (columns.status_code(name) for name in ("pending", "ok", "failed"))
# The /analysis products the report reads (schemas/archive.md, "/analysis").
BOUNDARY, BOUNDARY_CURVE = "analysis/boundary", "analysis/boundary_curve"
SENSITIVITY, DISPERSION = "analysis/sensitivity", "analysis/dispersion"


def _text(value):
    """An HDF5 attribute as Python text or list of text."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.dtype.kind in "OSU":
        return [_text(v) for v in value.tolist()]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


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


RUN_STATUS = columns.runs_path("status")


def design_path(name):
    """The dataset of a parameter the archive lists in /design@parameters."""
    return f"{columns.DESIGN_GROUP}/{name}"


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


class Archive:
    """One archive: attributes, parameters per run, result columns, series."""

    is_risk = False

    def __init__(self, path, checked):
        self.path = path
        self.snapshot = bool(checked["snapshot"])  # being written by a sweep, or its writer died
        self.notes = list(checked["notes"])
        self.file = hdf5.open_checked(path, checked)
        self.attrs = {k: _text(v) for k, v in self.file.attrs.items()}
        self.run_count = int(self.attrs.get("run_count", 0))
        self.status = self.file[RUN_STATUS][...]  # before any value (snapshot safety)
        self.complete = self.status != STATUS_PENDING
        self.ok = self.status == STATUS_OK
        design = self.file[columns.DESIGN_GROUP]
        self.design_attrs = {k: _text(v) for k, v in design.attrs.items()}
        self.design_names = list(self.design_attrs.get("parameters", []))
        names = self.design_attrs.get("unswept_parameter_names", [])
        values = self.design_attrs.get("unswept_parameter_values", [])
        self.unswept = dict(zip(names, values))
        self.aircraft = Aircraft(self.attrs.get("aircraft_text", ""))
        self.study_name = self.attrs.get("study_name", path)
        self._cache = {}  # per-run datasets already read (each is read once)

    def close(self):
        self.file.close()

    def has(self, path):
        return path in self.file

    def counts(self):
        """Runs by status: (ok, failed, pending)."""
        return (int(np.count_nonzero(self.status == STATUS_OK)), int(np.count_nonzero(self.status == STATUS_FAILED)),
                int(np.count_nonzero(self.status == STATUS_PENDING)))

    def param(self, name):
        """Value of a parameter for every run (swept or fixed), or None when the archive has neither."""
        if name in self.design_names:
            return self._read(design_path(name))
        if name in self.unswept:
            return np.full(self.run_count, float(self.unswept[name]))
        return None

    def levels(self, path):
        if path not in self.file:
            return []
        return _text(self.file[path].attrs.get("levels", []))

    def column(self, path):
        """A per-run scalar dataset as float64 (an integer column's fill value as NaN), all rows."""
        if path not in self._cache:
            dataset = self.file[path]
            values = dataset[...].astype(float)
            fill = dataset.attrs.get("fill")
            if fill is not None:
                values[values == float(fill)] = math.nan
            self._cache[path] = values
        return self._cache[path]

    def _read(self, path):
        if path not in self._cache:
            self._cache[path] = self.file[path][...]
        return self._cache[path]

    def series(self, path, rows):
        """Rows `rows` of a time series dataset."""
        dataset = self.file[path]
        return np.stack([dataset[int(r)] for r in rows]) if len(rows) else np.empty((0, dataset.shape[1]))

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
        values = np.stack([self._read(design_path(a))[complete] for a in axes], axis=1)
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
        return self.levels(design_path(name)) or None

    def read(self, path):
        """A whole dataset (a per-run column, a time axis, a product's dataset), read once."""
        return self._read(path)

    def is_dispersion(self):
        """Whether the archive is a dispersion study: it has /analysis/dispersion, or its runs fly in
        turbulence. Such an archive is shown in its own section only (docs/report.md)."""
        if DISPERSION in self.file:
            return True
        turbulence = self.param("turbulence")
        if turbulence is None:
            return False
        levels = self.levels(design_path("turbulence")) or report_labels.parameter("turbulence")["levels"]
        return any(levels[int(v)] != "none" for v in np.unique(turbulence[self.complete]) if np.isfinite(v))

    def boundary_curve(self):
        """/analysis/boundary_curve (gesweep boundary --archive: H*(u0) by continuation) as a dict of
        arrays (speed_mps, height_m, branch), or None."""
        if BOUNDARY_CURVE not in self.file:
            return None
        group = self.file[BOUNDARY_CURVE]
        return {name: group[name][...] for name in ("speed_mps", "height_m", "branch")}

    def sensitivity_products(self):
        """Every /analysis/sensitivity result group (gesweep sensitivity) as a dict: path, attrs (text),
        datasets (name -> array) and units (name -> text)."""
        products = []
        for path in self.analysis_groups(SENSITIVITY):
            group = self.file[path]
            products.append({"path": path, "attrs": {k: _text(v) for k, v in group.attrs.items()},
                             "datasets": {n: d[...] for n, d in group.items() if hdf5.is_dataset(d)},
                             "units": {n: _text(d.attrs.get("units", "")) for n, d in group.items()
                                       if hdf5.is_dataset(d)}})
        return products

    def dispersion(self):
        """/analysis/dispersion (gesweep dispersion, docs/dispersion.md) as a dict: attrs (text), the
        groups' labels and values, the limits (or None), and `members(g)`: the ok runs of group g; or
        None when the archive has none."""
        if DISPERSION not in self.file:
            return None
        product = self.file[DISPERSION]
        attrs = {k: _text(v) for k, v in product.attrs.items()}
        keys = product["group_value"][...]
        group_path = attrs.get("group_path", "")
        grouping = self._read(group_path) if group_path and group_path in self.file else None
        limits = None
        if "limits" in product and "probability" in product["limits"]:
            limits = {name: (_text(d[...]) if d.dtype.kind in "OS" else d[...])
                      for name, d in product["limits"].items() if hdf5.is_dataset(d)}

        def members(index):
            if grouping is None:
                return self.ok
            return self.ok & (np.isnan(grouping) if np.isnan(keys[index]) else grouping == keys[index])

        return {"attrs": attrs, "labels": _text(product["group_label"][...]), "values": keys,
                "limits": limits, "members": members, "group_by": attrs.get("group_by", ""),
                "column_paths": list(attrs.get("column_paths", [])), "columns": list(attrs.get("columns", [])),
                "column_units": list(attrs.get("column_units", []))}

    def analysis_groups(self, prefix):
        """Groups under `prefix` (e.g. analysis/sensitivity) that carry a `method` attribute."""
        found = []
        if prefix not in self.file:
            return found

        def visit(name, obj):
            if hdf5.is_group(obj) and "method" in obj.attrs and not name.split("/")[-1].startswith("."):
                found.append(prefix + "/" + name)

        self.file[prefix].visititems(visit)
        return sorted(found)

    def boundary(self):
        """/analysis/boundary as a dict of arrays (with 'keys', 'levels', 'attrs'), or None."""
        if BOUNDARY not in self.file:
            return None
        group = self.file[BOUNDARY]
        out = {"attrs": {k: _text(v) for k, v in group.attrs.items()}}
        for name, dataset in group.items():
            if dataset.dtype.kind == "O":
                out[name] = [v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v) for v in dataset[...]]
            else:
                out[name] = dataset[...]
            out.setdefault("levels", {})[name] = _text(dataset.attrs.get("levels", []))
        out["keys"] = list(out["attrs"].get("keys", []))
        return out


class RiskArchive:
    """A subset-simulation archive of `gesweep risk` (docs/dispersion.md, "Landing risk by subset
    simulation"; schemas/archive.md, "Subset-simulation archives"): its estimates (result_json), the
    evaluations and the design points' series. The engine's check (its kind, version, equal lengths of
    the evaluation columns, the value matrix's width, tags and statuses in range) has passed before it
    is opened; what is checked here is the report's own reading: each estimate's runs equal to the
    count of the rows it takes for the estimate's cell and limit."""

    is_risk = True
    snapshot = False

    def __init__(self, path, checked):
        self.path = path
        self.notes = list(checked["notes"])
        self.file = hdf5.open_checked(path, checked)
        self.attrs = {k: _text(v) for k, v in self.file.attrs.items()}
        self.result = json.loads(self.attrs["result_json"])
        e = self.file["subset/evaluations"]
        self.columns = [str(c) for c in _text(e.attrs["columns"])]
        self.evaluations = {k: e[k][...] for k in ("cell", "limit", "level", "chain", "step", "status", "g")}
        n = len(self.evaluations["g"])
        self.values = e["values"][...]
        # A limit's index among its cell's limits: its order in result_json within the cell.
        self._index, seen = {}, {}
        for limit in self.result["limits"]:
            self._index[id(limit)] = seen.get(limit["cell"], 0)
            seen[limit["cell"]] = self._index[id(limit)] + 1
        for limit in self.result["limits"]:
            rows = self.rows(limit)
            if int(rows.sum()) != int(limit["runs"]):
                raise ValueError(f"{path}: {limit['limit']} counts {limit['runs']} runs, its rows are {int(rows.sum())}")
        self.run_count = n
        self.study_name = self.result.get("study", path)
        self.aircraft = Aircraft("")

    def limit_index(self, limit):
        """The limit's index among its cell's limits (its order in result_json within the cell)."""
        return self._index[id(limit)]

    def counts(self):
        status = self.evaluations["status"]
        return int((status == STATUS_OK).sum()), int((status == STATUS_FAILED).sum()), 0

    def rows(self, limit, level=None):
        """The rows of a limit's evaluations (of one level, or all)."""
        e = self.evaluations
        rows = (e["cell"] == limit["cell"]) & (e["limit"] == self.limit_index(limit))
        return rows & (e["level"] == level) if level is not None else rows

    def column(self, name):
        """The index in the value matrix of the column named `name` (its last path component)."""
        return next(i for i, c in enumerate(self.columns) if c.rsplit("/", 1)[-1] == name)

    def design_series(self, limit):
        """{series name: {column: array}} of a limit's design point ("steady", "mean_failure",
        "most_likely"), or {} when none of its runs failed."""
        name = f"subset/design_points/cell_{limit['cell']}_limit_{self.limit_index(limit)}"
        if name not in self.file:
            return {}
        group = self.file[name]
        return {k: {c: d[...] for c, d in group[k].items()} for k in group if hdf5.is_group(group[k])}

    def close(self):
        self.file.close()


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
    except (KeyError, TypeError) as error:  # a layout the report cannot read as it expects
        for archive in archives:
            archive.close()
        raise ValueError(f"{checked['path']}: cannot read it as a gesweep archive ({error})") from None
    except (OSError, ValueError):
        for archive in archives:
            archive.close()
        raise
    return archives
