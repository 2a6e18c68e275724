"""gesweep.open_archive: an archive (schemas/archive.md) as a lazy xarray.Dataset (docs/python.md).

A grid design becomes named dimensions, one per swept parameter, with the grid's axis values as
coordinates; any other design (list, lhs, sobol, morris, a shard of a grid) a `run` dimension with the
design columns as its coordinates. Nothing but runs/status (and the small design axes) is read when
the archive is opened: every variable is a lazily indexed view of its HDF5 dataset (no dask), read
when its values are asked for, and only the rows asked for. Runs not complete (pending) or failed are
masked: NaN in every result (integer codes become float64 so that they can hold NaN).
"""

import os
import warnings

import numpy as np
import xarray as xr
from xarray.backends import BackendArray
from xarray.core import indexing

from . import _hdf5  # the one reader of archive files, shared with scripts/report


def _layout():
    """The archive's layout (groups, runs/, run statuses, /analysis products) as the native module
    carries it: the column manifest's keys, from the engine's writers (gesweep columns --json)."""
    from ._gesweep import _archive_layout
    return _hdf5.Layout(_archive_layout)


class ArchiveNote(UserWarning):
    """What opening an archive could not check (an archive merged before shard identities), as the
    gesweep command's "note:" line says it."""


def _input_error(source, key, value, expected):
    """gesweep.InputError with the attributes the engine's carry, worded as the engine words it."""
    from ._gesweep import InputError
    text = source + (f": {key}" if key else "") + (f" = {value}" if value else "") + f": {expected}"
    error = InputError(text)
    error.source, error.key, error.value, error.expected = source, key, value, expected
    return error


def _open_checked(path):
    """The archive at `path` opened (_hdf5.SweepArchive, the one reader: runs/status read), after the checks every gesweep command makes before it
    reads a value (the engine's ArchiveReader::Open, the one checker: the file, its layout, and a
    virtual archive's shard files -- missing, replaced, moved, foreign, itself, cyclic): those refuse
    with gesweep.InputError in the command's words; a note on what could not be checked is an
    ArchiveNote warning."""
    from ._gesweep import _check_archive
    try:
        name = os.fspath(path)
    except TypeError:
        raise _input_error("argument", "path", repr(path), "expected a path (str or os.PathLike)") from None
    if isinstance(name, bytes):
        name = os.fsdecode(name)
    checked = _check_archive(name)
    for note in checked["notes"]:
        warnings.warn(note, ArchiveNote, stacklevel=3)
    try:
        return _hdf5.SweepArchive(name, checked, _layout())
    except OSError as error:  # changed between the check and the open
        raise _input_error(name, "", "", f"cannot open the archive: {error}") from None


_text = _hdf5.text


def _attrs(dataset):
    """A dataset's attributes (_hdf5.attrs) and its HDF5 path."""
    out = _hdf5.attrs(dataset)
    out["path"] = dataset.name.lstrip("/")
    return out


class _RunRows(BackendArray):
    """The rows of a per-run dataset (first axis: runs), reshaped to the grid's axes when there is one,
    with the runs that are not ok masked."""

    def __init__(self, dataset, ok, grid_shape):
        self.dataset = dataset
        self.ok = ok  # bool per run, or None: nothing masked
        self.grid_shape = tuple(grid_shape)  # () for a run dimension
        stored = dataset.dtype
        if stored.names and set(stored.names) == {"re", "im"}:
            self.dtype = np.dtype(np.complex128)
        elif stored.kind in "iub" and ok is not None and not ok.all():
            self.dtype = np.dtype(np.float64)
        else:
            self.dtype = stored
        rest = dataset.shape[1:]
        self.shape = (self.grid_shape or (dataset.shape[0],)) + tuple(rest)

    def __getitem__(self, key):
        return indexing.explicit_indexing_adapter(key, self.shape, indexing.IndexingSupport.OUTER, self._read)

    def _read(self, key):
        axes = len(self.grid_shape) or 1
        run_key, rest_key = key[:axes], tuple(key[axes:])
        if self.grid_shape:
            # The runs the grid indices select, in C order (the last parameter fastest).
            per_axis = [np.arange(n)[k] for n, k in zip(self.grid_shape, run_key)]
            scalar = [np.ndim(k) == 0 for k in per_axis]
            mesh = np.ix_(*[np.atleast_1d(k) for k in per_axis])
            rows = np.ravel_multi_index(mesh, self.grid_shape)
        else:
            rows = np.arange(self.dataset.shape[0])[run_key[0]]
            scalar = [np.ndim(rows) == 0]
        flat = np.atleast_1d(rows).ravel()
        if flat.size == 0:
            values = np.empty((0,) + self.dataset.shape[1:], dtype=self.dataset.dtype)
        else:
            lo, hi = int(flat.min()), int(flat.max()) + 1
            block = self.dataset[(slice(lo, hi),) + rest_key] if rest_key else self.dataset[lo:hi]
            values = block[flat - lo]
        if values.dtype.names and set(values.dtype.names) == {"re", "im"}:
            values = values["re"] + 1j * values["im"]
        values = values.astype(self.dtype, copy=False)
        if self.ok is not None:
            bad = ~self.ok[flat]
            if bad.any():
                values = values.copy() if values.base is not None else values
                if values.dtype.kind == "c":
                    values[bad] = complex(np.nan, np.nan)
                elif values.dtype.kind == "f":
                    values[bad] = np.nan
        shape = np.atleast_1d(rows).shape + values.shape[1:]
        values = values.reshape(shape)
        # Integer indices drop their axis (outer indexing).
        drop = tuple(i for i, s in enumerate(scalar) if s)
        if drop:
            values = values.reshape(tuple(n for i, n in enumerate(values.shape) if i not in drop))
        return values


class _Whole(BackendArray):
    """A dataset that is not per run (an axis, an /analysis product), read when asked."""

    def __init__(self, dataset):
        self.dataset = dataset
        stored = dataset.dtype
        self.dtype = np.dtype(np.complex128) if stored.names and set(stored.names) == {"re", "im"} else stored
        if stored.kind == "S":
            self.dtype = np.dtype(object)
        self.shape = dataset.shape

    def __getitem__(self, key):
        return indexing.explicit_indexing_adapter(key, self.shape, indexing.IndexingSupport.OUTER, self._read)

    def _read(self, key):
        values = self.dataset[()] if self.shape == () else self.dataset[key]
        if isinstance(values, np.ndarray) and values.dtype.names and set(values.dtype.names) == {"re", "im"}:
            values = values["re"] + 1j * values["im"]
        if isinstance(values, np.ndarray) and values.dtype.kind == "S":
            values = np.array(_text(values), dtype=object)
        return values


def _lazy(array):
    return indexing.LazilyIndexedArray(array)


def _design_link(f, layout, obj, name):
    """Whether `obj` at results|series/<analysis>/`name` is the netCDF view's link to design/`name`
    (schemas/archive.md, "netCDF view"), not a column of its own."""
    other = f.get(layout.design_path(name)) if "/" not in name else None
    return _hdf5.is_dataset(other) and other == obj


def _names(f, layout):
    """Variable name of each results/<analysis>/<leaf> and series/<analysis>/<leaf>: the leaf (with
    '/' as '_'), or '<analysis>_<leaf>' where two analyses, or a design column, share a leaf."""
    entries = []
    series = layout.group("series")
    for group in (layout.group("results"), series):
        if group not in f:
            continue
        for analysis in f[group]:
            def visit(name, obj, group=group, analysis=analysis):
                if _hdf5.is_dataset(obj) and not _design_link(f, layout, obj, name):
                    entries.append((group, analysis, name))
            f[group][analysis].visititems(visit)
    taken = set(f[layout.group("design")]) if layout.group("design") in f else set()
    leaves = {}
    for group, analysis, name in entries:
        if group == series and name == "time_s":
            continue
        leaves.setdefault(name.replace("/", "_"), []).append((group, analysis, name))
    out = {}
    for leaf, users in leaves.items():
        unique = len(users) == 1 and leaf not in taken and leaf not in ("status", "message", "run")
        for group, analysis, name in users:
            out[f"{group}/{analysis}/{name}"] = leaf if unique else f"{analysis}_{leaf}"
    return out


def _design(archive):
    design = archive.file.get(archive.layout.group("design"))
    if design is None:
        return {}, [], None
    return archive.design_attrs, list(archive.design_names), design


def _axis_coordinate(dataset):
    values = np.asarray(dataset.attrs["axis_values"], dtype=float)
    levels = dataset.attrs.get("levels")
    attrs = _attrs(dataset)
    attrs.pop("axis_values", None)
    if levels is not None:
        names = _text(list(levels))
        if names == ["false", "true"]:  # a boolean: True and False
            return values.astype(bool), attrs
        return np.array(names, dtype=object)[values.astype(int)], attrs
    return values, attrs


def open_archive(path, product=None):
    """An archive as an xarray.Dataset (lazy: only runs/status is read on opening).

    product: None for the runs (design, results, series); a name under /analysis (see
    list_products(path)), e.g. "boundary", for that product as a Dataset of its own.

    A grid design gives one dimension per swept parameter, in the design's order, with its axis values
    as the coordinate (a choice's level names, a boolean's True and False), so that
    ``ds.stability_margin_per_s.sel(speed_mps=32, method="nearest").plot()`` works; any other design a
    `run` dimension with the design columns as coordinates. Every results/<analysis>/<name> is a
    variable named <name> ('/' as '_'; <analysis>_<name> where analyses share a name), every
    series/<analysis>/<name> too, over the time axis time_s; eigenvalues over `eigenvalue` (5). attrs
    of each: units, description, levels, path (its HDF5 path). Runs that are pending or failed are
    NaN; `status` (its `levels` attribute names the codes: pending, ok, failed) says which. ds.attrs: the archive's root attributes.
    Virtual archives of `gesweep merge` read their shards in place (keep them beside it).

    Before h5py reads anything, the archive is checked as every gesweep command checks it: a file
    that is not an archive, a damaged one, or a virtual archive one of whose shard files is missing,
    replaced, moved, of another study, the archive itself or part of a cycle raises gesweep.InputError
    with the command's words; an archive merged before shard identities gives an ArchiveNote warning.
    """
    if product is not None and not isinstance(product, str):
        raise _input_error("argument", "product", repr(product),
                           "expected the name of a product under /analysis (a str; see list_products), or None")
    archive = _open_checked(path)
    if product is not None:
        return _open_product(archive, product)
    f, layout = archive.file, archive.layout
    status_path = layout.runs_path("status")
    status, ok = archive.status, archive.ok
    mask = None if ok.all() else ok
    n = status.shape[0]
    design_attrs, parameters, design = _design(archive)
    grid = (design is not None and design_attrs.get("kind") == "grid" and parameters
            and int(np.prod(design.attrs["shape"])) == n
            and all("axis_values" in design[p].attrs for p in parameters))

    coords, variables = {}, {}
    if grid:
        run_dims = tuple(parameters)
        grid_shape = tuple(int(s) for s in design.attrs["shape"])
        for p in parameters:
            values, attrs = _axis_coordinate(design[p])
            coords[p] = xr.Variable((p,), values, attrs)
        variables["status"] = xr.Variable(run_dims, status.reshape(grid_shape), _attrs(f[status_path]))
    else:
        run_dims = ("run",)
        grid_shape = ()
        coords["run"] = xr.Variable(("run",), np.arange(n), {"description": "row of the archive"})
        if design is not None:
            for p in parameters:
                coords[p] = xr.Variable(("run",), _lazy(_RunRows(design[p], None, ())), _attrs(design[p]))
        variables["status"] = xr.Variable(("run",), status, _attrs(f[status_path]))

    names = _names(f, layout)
    time_dims = {}
    series = layout.group("series")
    if series in f:
        groups = list(f[series])
        for analysis in groups:
            if "time_s" in f[series][analysis]:
                dim = "time_s" if len(groups) == 1 else f"{analysis}_time_s"
                time_dims[analysis] = dim
                axis = f[series][analysis]["time_s"]
                coords[dim] = xr.Variable((dim,), axis[:], _attrs(axis))
    for path, name in names.items():
        dataset = f[path]
        if dataset.ndim == 0 or dataset.shape[0] != n:
            continue
        group, analysis = path.split("/")[:2]
        extra = []
        for axis in range(1, dataset.ndim):
            if group == series and axis == 1 and analysis in time_dims:
                extra.append(time_dims[analysis])
            elif dataset.name.endswith("/eigenvalues"):
                extra.append("eigenvalue")
            else:
                extra.append(f"{name}_component")
                components = dataset.attrs.get("component_names")
                if components is not None and f"{name}_component" not in coords:
                    coords[f"{name}_component"] = xr.Variable((f"{name}_component",),
                                                              np.array(_text(list(components)), dtype=object))
        variables[name] = xr.Variable(run_dims + tuple(extra), _lazy(_RunRows(dataset, mask, grid_shape)),
                                      _attrs(dataset))
    attrs = {k: _text(v) for k, v in f.attrs.items()
             if not isinstance(v, np.ndarray) or v.dtype.kind in "SUOifu"}
    attrs["design_kind"] = design_attrs.get("kind", "")
    attrs["design_parameters"] = parameters
    ds = xr.Dataset(variables, coords=coords, attrs=attrs)
    ds.set_close(f.close)
    return ds


def list_products(path):
    """The names of an archive's /analysis products (`gesweep boundary --archive`, `gesweep sensitivity`,
    `gesweep dispersion`), as the archive layout names them."""
    with _open_checked(path) as archive:
        return sorted(archive.products())


def _open_product(archive, product):
    f = archive.file
    available = sorted(archive.products())
    # A product by its name, or a group inside one ("sensitivity/boundary/height_m").
    first, _, rest = product.partition("/")
    key = None
    if first in archive.layout.product_names():
        key = archive.layout.product_root(first) + (f"/{rest}" if rest else "")
    if key is None or key not in f:
        filename = f.filename
        f.close()
        from ._gesweep import InputError
        raise InputError(f"{filename}: product = {product}: expected one of "
                         f"{', '.join(available) or '(none: the archive has no /analysis products)'}")
    group = f[key]
    variables = {}
    lengths = {}

    def visit(name, obj):
        if _hdf5.is_dataset(obj):
            dims = []
            for axis, size in enumerate(obj.shape):
                if axis == 0:
                    dim = lengths.setdefault(size, "row" if not lengths else f"row_{size}")
                else:
                    dim = f"{name.replace('/', '_')}_dim{axis}"
                dims.append(dim)
            variables[name.replace("/", "_")] = xr.Variable(tuple(dims), _lazy(_Whole(obj)), _attrs(obj))
    group.visititems(visit)
    attrs = {k: _text(v) for k, v in group.attrs.items()}
    ds = xr.Dataset(variables, attrs=attrs)
    ds.set_close(f.close)
    return ds
