"""The one reader of archive files in Python: gesweep.open_archive and scripts/report both open and read
archives here, and only after the engine has checked them (docs/python.md, docs/report.md, "One reader").

Pure Python over h5py: it imports nothing of the native module, so that scripts/report, which runs
beside a gesweep binary and not always beside the module, loads this file as it is (load_shared in
scripts/report/report_data.py). What the engine's check says of an archive (gesweep check --format json,
or the module's _check_archive: the same ArchiveReader::Open) is the only validation: nothing here
mirrors a check of the engine.

Every path it reads comes from the archive's layout as the column manifest lists it (`gesweep columns
--json`: `groups`, `runs`, `run_status`, `products`, `subset_archive`; the module carries the same keys
as gesweep._gesweep._archive_layout), built from what the engine's writers store: a `Layout` of either.
A name asked of the layout that it does not list (a product, a dataset, an attribute) fails at once with
one line (LayoutError), not as a KeyError of h5py. What this module still checks is its own reading: a
subset-simulation estimate's runs equal to the rows it takes for it.
"""

import json
import math

import h5py
import numpy as np

# The kinds of HDF5 object an archive holds (schemas/archive.md): for isinstance, so that a reader of
# archives names h5py nowhere else.
Dataset, Group = h5py.Dataset, h5py.Group

# What `gesweep check` and the module's check call a sweep's archive and a subset-simulation archive.
KIND_RUNS, KIND_SUBSET = "runs", "subset_simulation"

# HDF5 dimension-scale bookkeeping attributes (not the archive's own).
_BOOKKEEPING = ("DIMENSION_LIST", "REFERENCE_LIST", "CLASS", "NAME", "_Netcdf4Dimid", "_Netcdf4Coordinates")

# The layout keys this module reads (the manifest has these besides its columns).
LAYOUT_KEYS = ("groups", "runs", "run_status", "products", "subset_archive")


class LayoutError(LookupError):
    """A reader asked the layout for a product, dataset or attribute it does not list."""


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


def values(dataset):
    """A whole dataset as NumPy (strings decoded to a list of str)."""
    if dataset.dtype.kind in "OS":
        return [v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v) for v in dataset[...]]
    return dataset[...]


class Layout:
    """The archive's layout: the manifest's `groups`, `runs`, `run_status`, `products` and
    `subset_archive` (the whole manifest of `gesweep columns --json`, or the module's _archive_layout)."""

    def __init__(self, manifest):
        missing = [key for key in LAYOUT_KEYS if key not in manifest]
        if missing:
            raise LayoutError(f"the column manifest has no {', '.join(missing)}: a gesweep older than this reader")
        self.manifest = manifest

    def group(self, kind):
        """The archive's top-level group of `kind` (runs, design, results, series, analysis)."""
        try:
            return self.manifest["groups"][kind]
        except KeyError:
            raise LayoutError(f"the archive layout has no group '{kind}'") from None

    def runs_path(self, name):
        """The path of a bookkeeping dataset ("status" gives "runs/status")."""
        for entry in self.manifest["runs"]:
            if entry["path"].split("/")[-1] == name:
                return entry["path"]
        raise LayoutError(f"the archive layout has no runs dataset '{name}'")

    def design_path(self, parameter):
        return f"{self.group('design')}/{parameter}"

    def status_code(self, name):
        """The /runs/status code of the run status `name` (RunStatus's names table)."""
        for entry in self.manifest["run_status"]:
            if entry["name"] == name:
                return entry["code"]
        raise LayoutError(f"the archive layout has no run status '{name}'")

    def product(self, name):
        """The layout entry of the /analysis product `name` (boundary, boundary_curve, sensitivity,
        dispersion)."""
        for entry in self.manifest["products"]:
            if entry["name"] == name:
                return entry
        raise LayoutError(f"the archive layout has no /analysis product '{name}'")

    def product_names(self):
        return [entry["name"] for entry in self.manifest["products"]]

    def product_root(self, name):
        """The group of a product: its path up to the first <placeholder> ("analysis/sensitivity")."""
        path = self.product(name)["path"]
        return path.split("/<", 1)[0]

    def subset(self, *names):
        """The layout entry of the subset-simulation archive's group at `names` (("evaluations",),
        ("design_points", "design_point")), or of the archive itself with no names."""
        entry = self.manifest["subset_archive"]
        for name in names:
            found = [g for g in entry["groups"] if g["name"] == name]
            if not found:
                raise LayoutError(f"the subset-simulation archive's layout has no group '{name}'")
            entry = found[0]
        return entry


def field(entry, name, kind="datasets"):
    """`name` when the layout entry lists it among its `kind` (datasets or attributes); LayoutError
    otherwise. The readers name what they read through this, so that a name the writer no longer
    stores fails here, with one line."""
    if any(f["name"] == name for f in entry[kind]):
        return name
    raise LayoutError(f"{entry['path'] or entry['name']} has no {kind[:-1]} '{name}' in the archive layout")


class _OpenFile:
    """An archive open read-only in `self.file`, closed by close() or on leaving a with block."""

    def close(self):
        self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class SweepArchive(_OpenFile):
    """A sweep's archive (schemas/archive.md), opened after the engine's check: attributes, parameters
    per run, result columns, series and the /analysis products. runs/status is read first, before any
    value (a snapshot's complete runs are those whose status was written, after their values)."""

    is_risk = False

    def __init__(self, path, checked, layout):
        self.path = path
        self.layout = layout
        self.snapshot = bool(checked.get("snapshot", False))
        self.notes = list(checked.get("notes", []))
        self.file = open_checked(path, checked)
        try:
            self.status = self.file[layout.runs_path("status")][...]
            self.attrs = {k: _plain(v) for k, v in self.file.attrs.items()}
            self.run_count = int(self.attrs.get("run_count", self.status.shape[0]))
            self.complete = self.status != layout.status_code("pending")
            self.ok = self.status == layout.status_code("ok")
            design = self.file.get(layout.group("design"))
            self.design_attrs = {k: _plain(v) for k, v in design.attrs.items()} if design is not None else {}
        except BaseException:
            self.file.close()
            raise
        parameters = self.design_attrs.get("parameters", [])
        self.design_names = [parameters] if isinstance(parameters, str) else list(parameters)
        self.unswept = dict(zip(self.design_attrs.get("unswept_parameter_names", []),
                                self.design_attrs.get("unswept_parameter_values", [])))
        self._cache = {}  # whole datasets already read (each is read once)

    def has(self, path):
        return path in self.file

    def counts(self):
        """Runs by status: (ok, failed, pending)."""
        return tuple(int(np.count_nonzero(self.status == self.layout.status_code(name)))
                     for name in ("ok", "failed", "pending"))

    def read(self, path):
        """A whole dataset (a per-run column, a time axis), read once."""
        if path not in self._cache:
            self._cache[path] = self.file[path][...]
        return self._cache[path]

    def column(self, path):
        """A per-run scalar dataset as float64 (an integer column's fill value as NaN), all rows."""
        key = ("float", path)
        if key not in self._cache:
            dataset = self.file[path]
            column = dataset[...].astype(float)
            fill = dataset.attrs.get("fill")
            if fill is not None:
                column[column == float(fill)] = math.nan
            self._cache[key] = column
        return self._cache[key]

    def levels(self, path):
        """The level names of a coded dataset, [] when it has none (or is not there)."""
        if path not in self.file:
            return []
        return text(self.file[path].attrs.get("levels", []))

    def param(self, name):
        """Value of a parameter for every run (swept or fixed), or None when the archive has neither."""
        if name in self.design_names:
            return self.read(self.layout.design_path(name))
        if name in self.unswept:
            return np.full(self.run_count, float(self.unswept[name]))
        return None

    def series(self, path, rows):
        """Rows `rows` of a time series dataset."""
        dataset = self.file[path]
        return np.stack([dataset[int(r)] for r in rows]) if len(rows) else np.empty((0, dataset.shape[1]))

    def products(self):
        """The names of the /analysis products the archive holds, among those the layout lists."""
        return [name for name in self.layout.product_names() if self.layout.product_root(name) in self.file]

    def product(self, name):
        """The /analysis product `name` whose path has no <placeholder> (boundary, boundary_curve,
        dispersion) as {"attrs", "datasets": name -> values, "levels": name -> level names}, or None."""
        entry = self.layout.product(name)
        if entry["path"] not in self.file:
            return None
        return _group_contents(self.file[entry["path"]])

    def boundary(self):
        """/analysis/boundary as its datasets by name, with "attrs", "levels" (name -> level names) and
        "keys" (the key datasets, in sort order); None when the archive has none."""
        product = self.product("boundary")
        if product is None:
            return None
        out = dict(product["datasets"])
        out["attrs"], out["levels"] = product["attrs"], product["levels"]
        out["keys"] = list(product["attrs"].get(field(self.layout.product("boundary"), "keys", "attributes"), []))
        return out

    def sensitivity_products(self):
        """Every result group of /analysis/sensitivity/<output> (a group with the attribute `method`) as
        {"path", "attrs", "datasets", "units"}, in path order."""
        root = self.layout.product_root("sensitivity")
        marker = field(self.layout.product("sensitivity"), "method", "attributes")
        if root not in self.file:
            return []
        found = []

        def visit(name, obj):
            if is_group(obj) and marker in obj.attrs and not name.split("/")[-1].startswith("."):
                found.append(f"{root}/{name}")

        self.file[root].visititems(visit)
        out = []
        for path in sorted(found):
            contents = _group_contents(self.file[path])
            out.append({"path": path, "attrs": contents["attrs"], "datasets": contents["datasets"],
                        "units": contents["units"]})
        return out

    def dispersion(self):
        """/analysis/dispersion (gesweep dispersion, docs/dispersion.md) as a dict: attrs, datasets, the
        groups' labels and values, the limits subgroup's datasets (or None), the columns' paths, names
        and units, and `members(g)`: the ok runs of group g (by the grouping column); None when the
        archive has none."""
        entry = self.layout.product("dispersion")
        product = self.product("dispersion")
        if product is None:
            return None
        a, d = product["attrs"], product["datasets"]
        keys = d[field(entry, "group_value")]
        group_path = a.get(field(entry, "group_path", "attributes"), "")
        grouping = self.read(group_path) if group_path and group_path in self.file else None
        limits_entry = [g for g in entry["groups"] if g["name"] == "limits"][0]
        limits_path = f"{entry['path']}/{limits_entry['path']}"
        limits = None
        if limits_path in self.file and field(limits_entry, "probability") in self.file[limits_path]:
            limits = _group_contents(self.file[limits_path])["datasets"]

        def members(index):
            if grouping is None:
                return self.ok
            return self.ok & (np.isnan(grouping) if np.isnan(keys[index]) else grouping == keys[index])

        return {"attrs": a, "datasets": d, "labels": list(d[field(entry, "group_label")]), "values": keys,
                "limits": limits, "members": members, "group_by": a.get(field(entry, "group_by", "attributes"), ""),
                "column_paths": list(a.get(field(entry, "column_paths", "attributes"), [])),
                "columns": list(a.get(field(entry, "columns", "attributes"), [])),
                "column_units": list(a.get(field(entry, "column_units", "attributes"), []))}

    def boundary_curve(self):
        """/analysis/boundary_curve (H*(u0) by continuation) as its datasets by name, or None."""
        product = self.product("boundary_curve")
        return None if product is None else product["datasets"]


class RiskArchive(_OpenFile):
    """A subset-simulation archive of `gesweep risk` (docs/dispersion.md, "Landing risk by subset
    simulation"; schemas/archive.md, "Subset-simulation archives"): its estimates (result_json), the
    evaluations and the design points' series. The engine's check (its kind, version, equal lengths of
    the evaluation columns, the value matrix's width, tags and statuses in range) has passed before it
    is opened; what is checked here is this reading: each estimate's runs equal to the count of the
    rows it takes for the estimate's cell and limit."""

    is_risk = True
    snapshot = False
    # The tags, status and limit state of each evaluation, as the layout names them.
    EVALUATION_DATASETS = ("cell", "limit", "level", "chain", "step", "status", "g")

    def __init__(self, path, checked, layout):
        self.path = path
        self.layout = layout
        self.notes = list(checked.get("notes", []))
        self.file = open_checked(path, checked)
        try:
            self._read()
        except BaseException:
            self.file.close()
            raise

    def _read(self):
        root = self.layout.subset()
        entry = self.layout.subset("evaluations")
        self.attrs = {k: _plain(v) for k, v in self.file.attrs.items()}
        self.result = json.loads(self.attrs[field(root, "result_json", "attributes")])
        e = self.file[entry["path"]]
        self.columns = [str(c) for c in text(e.attrs[field(entry, "columns", "attributes")])]
        self.evaluations = {k: e[field(entry, k)][...] for k in self.EVALUATION_DATASETS}
        self.values = e[field(entry, "values")][...]
        self.run_count = len(self.evaluations["g"])
        # A limit's index among its cell's limits: its order in result_json within the cell.
        self._index, seen = {}, {}
        for limit in self.result["limits"]:
            self._index[id(limit)] = seen.get(limit["cell"], 0)
            seen[limit["cell"]] = self._index[id(limit)] + 1
        for limit in self.result["limits"]:
            rows = self.rows(limit)
            if int(rows.sum()) != int(limit["runs"]):
                raise ValueError(f"{self.path}: {limit['limit']} counts {limit['runs']} runs, its rows are "
                                 f"{int(rows.sum())}")

    def limit_index(self, limit):
        """The limit's index among its cell's limits (its order in result_json within the cell)."""
        return self._index[id(limit)]

    def counts(self):
        """Landings by status: (ok, failed, pending); a pending landing is never stored."""
        status = self.evaluations["status"]
        return (int((status == self.layout.status_code("ok")).sum()),
                int((status == self.layout.status_code("failed")).sum()), 0)

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
        points = self.layout.subset("design_points")
        point = self.layout.subset("design_points", "design_point")
        name = (point["path"].replace("<cell>", str(limit["cell"]))
                .replace("<limit>", str(self.limit_index(limit))))
        path = f"{points['path']}/{name}"
        if path not in self.file:
            return {}
        group = self.file[path]
        return {k: {c: d[...] for c, d in group[k].items()} for k in group if is_group(group[k])}


def _plain(value):
    """An attribute as plain Python: text decoded, arrays as lists, NumPy scalars as Python numbers."""
    value = text(value)
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _group_contents(group):
    """A product group's attributes, datasets (read whole: products are small), their units and levels."""
    out = {"attrs": {k: _plain(v) for k, v in group.attrs.items()}, "datasets": {}, "units": {}, "levels": {}}
    for name, dataset in group.items():
        if not is_dataset(dataset):
            continue
        out["datasets"][name] = values(dataset)
        out["units"][name] = text(dataset.attrs.get("units", ""))
        out["levels"][name] = text(dataset.attrs.get("levels", []))
    return out


def open_archive(checked, layout):
    """The archive `checked` describes (an entry of `gesweep check --format json`, or the module's check
    with its `path` and `kind`) opened as a SweepArchive or a RiskArchive; ValueError, one line, for a
    kind this reader does not read."""
    kind = checked.get("kind", KIND_RUNS)
    if kind == KIND_SUBSET:
        return RiskArchive(checked["path"], checked, layout)
    if kind == KIND_RUNS:
        return SweepArchive(checked["path"], checked, layout)
    raise ValueError(f"{checked['path']}: an archive of a kind this reader does not read ({kind})")
