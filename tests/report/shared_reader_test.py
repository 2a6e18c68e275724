#!/usr/bin/python3
"""The one Python reader of archives (engine/python/gesweep/_hdf5.py, which gesweep.open_archive and
scripts/report share) reads what the engine's own reader prints for the same files (issue 29, item 4).

    /usr/bin/python3 tests/report/shared_reader_test.py GESWEEP

The independent reader is the command line: `gesweep query` (ArchiveReader and the column catalogue)
for a sweep's runs, `gesweep dispersion --format json` for the /analysis/dispersion product it has just
written and for a subset-simulation archive of `gesweep risk`. The numbers compared are the engine's on
both sides; what is tested is that the shared reader finds them where the manifest's layout says they
are, decodes them (levels, fill values, strings, the status codes by name) and groups them as the
command line does.
"""
import importlib.util
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np

GESWEEP = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else None
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ANCE = os.path.join(ROOT, "studies", "aircraft", "ance.toml")
os.environ["GESWEEP_BINARY"] = GESWEEP or os.path.join(ROOT, "build", "gesweep")
os.environ.pop("GESWEEP_COLUMNS_MANIFEST", None)  # the engine's manifest
sys.path.insert(0, os.path.join(ROOT, "scripts", "lib"))
import columns  # noqa: E402

# Short turbulent landings from 30 m (about a millisecond each): a sweep of 2 winds x 2 plants x 12
# seeds, and a subset simulation of a firm-landing limit reached by a few per cent of them.
SWEEP = '''format_version = 1
name = "shared_reader_sweep"
aircraft = "{aircraft}"
[analyses.landing]
[parameters]
height_m = 30.0
speed_mps = 52.21
wind_shear = "logarithmic"
turbulence = "dryden"
[design]
kind = "grid"
[[design.parameter]]
name = "wind_20ft_mps"
values = [-7.716667, -15.433333]
[[design.parameter]]
name = "h_derivatives"
values = [true, false]
[[design.parameter]]
name = "seed"
linspace = [0, 11, 12]
'''
RISK = '''format_version = 1
name = "shared_reader_risk"
aircraft = "{aircraft}"
[analyses.landing]
[parameters]
height_m = 30.0
speed_mps = 52.21
wind_shear = "logarithmic"
turbulence = "dryden"
wind_20ft_mps = -15.433333
[subset]
limits = ["touchdown_sink_rate_mps > 1.83"]
level_probability = 0.1
samples_per_level = 100
max_levels = 3
seed = 7
'''
LIMIT = "touchdown_sink_rate_mps > 1.6"
# The dispersion's grouping column and the fits the product stores (their law names in the JSON).
GROUP_BY = "wind_20ft_mps"
LAWS = ("normal", "gumbel_max", "gumbel_min", "gev_max")


def load_reader():
    """engine/python/gesweep/_hdf5.py loaded as a file, as the report loads it."""
    spec = importlib.util.spec_from_file_location(
        "gesweep_hdf5_test", os.path.join(ROOT, "engine", "python", "gesweep", "_hdf5.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


hdf5 = load_reader()


def gesweep(*args):
    out = subprocess.run([os.environ["GESWEEP_BINARY"], *map(str, args)], capture_output=True, text=True,
                         cwd=ROOT, timeout=600)
    if out.returncode != 0:
        raise AssertionError(f"gesweep {' '.join(map(str, args))}: {out.stderr.strip()}")
    return out.stdout


def checked(path):
    """The engine's check of one archive (`gesweep check --format json`)."""
    (entry,) = json.loads(gesweep("check", "--format", "json", "--", path))
    return entry


def setUpModule():
    global WORK, SWEEP_H5, RISK_H5, LAYOUT
    WORK = tempfile.mkdtemp(prefix="gesweep_shared_reader_")
    for name, text in (("sweep.toml", SWEEP), ("risk.toml", RISK)):
        with open(os.path.join(WORK, name), "w", encoding="utf-8") as f:
            f.write(text.format(aircraft=ANCE))
    SWEEP_H5, RISK_H5 = os.path.join(WORK, "sweep.h5"), os.path.join(WORK, "risk.h5")
    gesweep("run", os.path.join(WORK, "sweep.toml"), "-o", SWEEP_H5, "-q")
    gesweep("risk", os.path.join(WORK, "risk.toml"), "-o", RISK_H5, "--threads", "2")
    LAYOUT = hdf5.Layout(columns.manifest())


def tearDownModule():
    shutil.rmtree(WORK, ignore_errors=True)


def same(a, b):
    """Equal numbers, NaN equal to NaN (the JSON's null)."""
    a = math.nan if a is None else float(a)
    b = math.nan if b is None else float(b)
    return (math.isnan(a) and math.isnan(b)) or a == b


class SweepArchive(unittest.TestCase):
    def test_runs_as_gesweep_query_prints_them(self):
        printed = json.loads(gesweep("query", SWEEP_H5, "--columns", "*", "--format", "json"))
        with hdf5.open_archive(checked(SWEEP_H5), LAYOUT) as archive:
            self.assertIsInstance(archive, hdf5.SweepArchive)
            ok, failed, pending = archive.counts()
            self.assertEqual(ok + failed + pending, printed["runs"])
            self.assertEqual(ok + failed, printed["complete"])
            self.assertEqual(int(archive.complete.sum()), printed["complete"])
            rows = printed["rows"]
            self.assertEqual(len(rows), printed["complete"])
            self.assertEqual(sorted(archive.design_names), sorted(["wind_20ft_mps", "h_derivatives", "seed"]))
            index = np.array([row["index"] for row in rows])
            compared = 0
            for column in printed["columns"]:
                path = column["path"]
                if not archive.has(path) or path == LAYOUT.runs_path("message"):
                    continue
                if path == LAYOUT.runs_path("status"):
                    # The status names the query prints are the codes the layout gives them.
                    codes = [LAYOUT.status_code(row[column["name"]]) for row in rows]
                    self.assertEqual(codes, archive.status[index].tolist())
                    self.assertEqual(archive.levels(path), column["levels"])
                    compared += 1
                    continue
                mine = archive.column(path)[index]
                levels = archive.levels(path)
                self.assertEqual(levels, column.get("levels", []), path)
                for row, value in zip(rows, mine):
                    shown = row[column["name"]]
                    if isinstance(shown, str):  # a level's name
                        self.assertEqual(levels[int(value)], shown, path)
                    elif isinstance(shown, bool):
                        self.assertEqual(bool(value), shown, path)
                    else:
                        self.assertTrue(same(value, shown), f"{path}: {value} != {shown}")
                compared += 1
            self.assertGreaterEqual(compared, 10)  # design, runs/ and the landing's results
            # A design parameter read as a parameter is its column.
            self.assertTrue(np.array_equal(archive.param("seed")[index], [row["seed"] for row in rows]))


class DispersionProduct(unittest.TestCase):
    def test_product_as_gesweep_dispersion_prints_it(self):
        printed = json.loads(gesweep("dispersion", SWEEP_H5, "--group-by", GROUP_BY, "--limit", LIMIT,
                                     "--format", "json"))
        self.assertIn("written", printed)
        with hdf5.open_archive(checked(SWEEP_H5), LAYOUT) as archive:
            self.assertIn("dispersion", archive.products())
            product = archive.dispersion()
            self.assertEqual(product["columns"], printed["columns"])
            self.assertEqual(product["column_units"], printed["column_units"])
            self.assertEqual(product["group_by"], printed["group_by"])
            self.assertEqual(product["labels"], [g["label"] for g in printed["groups"]])
            d = product["datasets"]
            self.assertEqual(len(printed["groups"]), 2)
            for g, group in enumerate(printed["groups"]):
                self.assertTrue(same(product["values"][g], group["value"]))
                for c, column in enumerate(group["columns"]):
                    for name in ("runs", "values", "failed", "without_value", "pending", "mean",
                                 "standard_deviation", "minimum", "maximum"):
                        self.assertTrue(same(d[name][g, c], column[name]), (name, g, c))
                    self.assertEqual(bool(d["no_spread"][g, c]), column["no_spread"])
                    for p, value in enumerate(column["percentiles"]):
                        self.assertTrue(same(d["percentile_values"][g, c, p], value))
                    for fit in column["fits"]:
                        self.assertIn(fit["law"], LAWS)
                        for part in ("location", "scale"):
                            self.assertTrue(same(d[f"{fit['law']}_{part}"][g, c], fit[part]), (fit["law"], part))
                    # The group's ok runs, as the reader selects them by the grouping column.
                    self.assertEqual(int(product["members"](g).sum()),
                                     column["runs"] - column["failed"] - column["pending"])
                (limit,) = group["limits"]
                self.assertEqual(product["limits"]["limit"], [LIMIT])
                for name in ("exceed", "values", "failed", "probability"):
                    self.assertTrue(same(product["limits"][name][g, 0], limit[name]), name)
                for side, end in enumerate(("lower", "upper")):
                    self.assertTrue(same(product["limits"][f"wilson_{end}"][g, 0], limit["wilson"][side]))
                    self.assertTrue(same(product["limits"][f"clopper_pearson_{end}"][g, 0],
                                         limit["clopper_pearson"][side]))


class RiskArchive(unittest.TestCase):
    def test_estimates_and_evaluations_as_gesweep_dispersion_prints_them(self):
        entry = checked(RISK_H5)
        self.assertEqual(entry["kind"], hdf5.KIND_SUBSET)
        printed = json.loads(gesweep("dispersion", RISK_H5, "--format", "json"))
        with hdf5.open_archive(entry, LAYOUT) as archive:
            self.assertIsInstance(archive, hdf5.RiskArchive)
            self.assertEqual(archive.result, {k: v for k, v in printed.items() if k != "archive"})
            (limit,) = archive.result["limits"]
            # Its evaluations: the limit's rows are its runs, each level's no more than the samples.
            self.assertEqual(int(archive.rows(limit).sum()), limit["runs"])
            levels = sorted(set(archive.evaluations["level"][archive.rows(limit)].tolist()))
            self.assertEqual(levels[0], 1)
            for level in levels:
                self.assertLessEqual(int(archive.rows(limit, level).sum()), 100)
            ok, failed, pending = archive.counts()
            self.assertEqual((ok + failed, pending), (archive.run_count, 0))
            self.assertEqual(archive.values.shape, (archive.run_count, len(archive.columns)))
            sink = archive.values[:, archive.column("touchdown_sink_rate_mps")]
            self.assertGreater(int(np.isfinite(sink).sum()), 0)
            # The limit is exceeded by some landings (a few per cent): its design point's three series.
            self.assertGreater(limit["probability"], 0)
            series = archive.design_series(limit)
            self.assertEqual(sorted(series), ["mean_failure", "most_likely", "steady"])
            for columns_of in series.values():
                self.assertIn("time_s", columns_of)


# The manifest's type names of the stored HDF5 types (schemas/archive.md).
STORED_TYPES = {("f", 8): "float64", ("i", 1): "int8", ("i", 4): "int32", ("i", 8): "int64"}


def stored_type(dataset):
    if dataset.dtype.kind in "OS" or h5py.check_string_dtype(dataset.dtype) is not None:
        return "string"
    return STORED_TYPES[(dataset.dtype.kind, dataset.dtype.itemsize)]


def compare_listing(test, group, entry, families=()):
    """Every dataset and attribute of the HDF5 `group` is listed by the layout `entry` with the type and
    units it is stored with, and every listed one (but a <family> and those of `families`) is there."""
    listed = {f["name"]: f for f in entry["datasets"]}
    for name, dataset in group.items():
        if not isinstance(dataset, h5py.Dataset):
            continue
        field = listed.get(name) or next((f for f in listed.values() if "<" in f["name"]
                                          and name.endswith(f["name"].split(">", 1)[-1])), None)
        test.assertIsNotNone(field, f"{group.name}/{name} is not in the layout")
        test.assertEqual(stored_type(dataset), field["type"], f"{group.name}/{name}")
        units = dataset.attrs.get("units")
        if units is not None and "<" not in field["units"] and not field["units"].startswith("see ") \
                and "the parameter" not in field["units"]:
            test.assertEqual(units.decode() if isinstance(units, bytes) else units, field["units"], name)
    for name in listed:
        if "<" not in name and name not in families:
            test.assertIn(name, group, f"{group.name}: the layout lists {name}")
    attributes = {f["name"] for f in entry["attributes"]}
    test.assertEqual(set(group.attrs) - attributes, set(), group.name)


class LayoutListsWhatIsWritten(unittest.TestCase):
    def test_dispersion_and_subset_archive(self):
        gesweep("dispersion", SWEEP_H5, "--group-by", GROUP_BY, "--limit", LIMIT, "--format", "json")
        product = LAYOUT.product("dispersion")
        with h5py.File(SWEEP_H5, "r") as f:
            compare_listing(self, f[product["path"]], product)
            (limits,) = product["groups"]
            compare_listing(self, f[product["path"]][limits["path"]], limits)
        root = LAYOUT.subset()
        with h5py.File(RISK_H5, "r") as f:
            self.assertEqual(set(f.attrs) - {a["name"] for a in root["attributes"]}, set())
            evaluations = LAYOUT.subset("evaluations")
            compare_listing(self, f[evaluations["path"]], evaluations)


class Layout(unittest.TestCase):
    def test_a_name_the_layout_does_not_list_is_one_line(self):
        for call, word in ((lambda: LAYOUT.product("no_such_product"), "no_such_product"),
                           (lambda: LAYOUT.status_code("no_such_status"), "no_such_status"),
                           (lambda: hdf5.field(LAYOUT.product("boundary"), "no_such_dataset"), "no_such_dataset"),
                           (lambda: LAYOUT.subset("no_such_group"), "no_such_group")):
            with self.assertRaises(hdf5.LayoutError) as raised:
                call()
            self.assertIn(word, str(raised.exception))
            self.assertNotIn("\n", str(raised.exception))

    def test_the_module_carries_the_manifests_layout(self):
        module = os.path.join(os.path.dirname(os.environ["GESWEEP_BINARY"]), "python")
        if not os.path.isdir(os.path.join(module, "gesweep")):
            self.skipTest(f"no built module beside {os.environ['GESWEEP_BINARY']}")
        code = "import json, gesweep._gesweep as g; print(json.dumps(g._archive_layout))"
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=module), timeout=120)
        self.assertEqual(out.returncode, 0, out.stderr)
        carried = json.loads(out.stdout)
        self.assertEqual(carried, {key: columns.manifest()[key] for key in hdf5.LAYOUT_KEYS})


if __name__ == "__main__":
    unittest.main()
