#!/usr/bin/python3
"""The column manifest (issue 15), `gesweep columns --json`, says what real archives hold (every dataset of a sweep of every analysis at its defaults, with time series,
has the manifest's path, type, width, units, description, levels, component names, time axis and
fill, and nothing else); the text table names every path; a bad --aircraft is one line, exit 2.
Run by ctest (tests/report/CMakeLists.txt) with the gesweep binary as the first argument.
"""
import json
import os
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np

GESWEEP = os.path.abspath(sys.argv.pop(1))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
AIRCRAFT = os.path.join(ROOT, "studies", "aircraft", "ance.toml")

# Every model analysis at its defaults, with time series at the default output_dt_s (the manifest's
# storage), one run; the verification models in a second study (they need no aircraft).
MODEL_STUDY = f"""format_version = 1
name = "columns_manifest_model"
aircraft = "{AIRCRAFT}"
[analyses.modes]
[analyses.flying_qualities]
[analyses.boundary]
[analyses.open_loop]
[analyses.landing]
[output]
time_series = true
[parameters]
height_m = 60.0
speed_mps = 52.21
[design]
kind = "grid"
[[design.parameter]]
name = "h_derivatives"
values = [true]
"""
VERIFICATION_STUDY = """format_version = 1
name = "columns_manifest_verification"
[analyses.ishigami]
[analyses.linear]
coefficients = [1.0, 2.0]
[design]
kind = "grid"
[[design.parameter]]
name = "x1"
values = [0.5]
[[design.parameter]]
name = "x2"
values = [0.25]
[[design.parameter]]
name = "x3"
values = [0.125]
"""
# The HDF5 types of the manifest's type names (complex128 is the compound {re, im} of float64).
H5_KINDS = {"float64": ("f", 8), "int8": ("i", 1), "int32": ("i", 4), "int64": ("i", 8), "uint64": ("u", 8)}


def gesweep(*args):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=600, cwd=ROOT)


def text(value):
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.ndarray):
        return [text(v) for v in value.tolist()]
    if isinstance(value, list):
        return [text(v) for v in value]
    return value


def design_link(file, path, obj):
    """The netCDF view's link results|series/<analysis>/<x> -> design/<x> (schemas/archive.md)."""
    other = file.get("design/" + path.rsplit("/", 1)[-1])
    return not path.startswith("design/") and isinstance(other, h5py.Dataset) and other == obj


def datasets(file, prefix):
    found = {}

    def visit(name, obj):  # returns None: visititems stops at the first other value
        if isinstance(obj, h5py.Dataset) and not design_link(file, prefix + "/" + name, obj):
            found[prefix + "/" + name] = obj

    file[prefix].visititems(visit)
    return found


class ColumnsManifest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        out = gesweep("columns", "--json")
        assert out.returncode == 0, out.stderr
        cls.printed = out.stdout
        cls.manifest = json.loads(out.stdout)
        cls.work = tempfile.TemporaryDirectory(prefix="gesweep_columns_test_")
        cls.archives = []
        for name, study in (("model", MODEL_STUDY), ("verification", VERIFICATION_STUDY)):
            study_path = os.path.join(cls.work.name, name + ".toml")
            with open(study_path, "w") as f:
                f.write(study)
            archive = os.path.join(cls.work.name, name + ".h5")
            run = gesweep("run", study_path, "-o", archive, "-q")
            assert run.returncode == 0, run.stderr
            cls.archives.append(archive)

    @classmethod
    def tearDownClass(cls):
        cls.work.cleanup()

    def test_archives_hold_exactly_the_manifests_columns(self):
        analyses = {a["name"]: a for a in self.manifest["analyses"]}
        seen = set()
        for archive in self.archives:
            with h5py.File(archive, "r") as f:
                names = text(f.attrs["analyses"])
                names = names if isinstance(names, list) else names.split(",")
                expected = {}
                for name in names:
                    seen.add(name)
                    for c in analyses[name]["columns"]:
                        expected[c["path"]] = c
                    for axis in analyses[name]["time_axes"]:
                        expected[axis["path"]] = dict(axis, type="float64", width=axis["samples"], axis=True)
                stored = {**datasets(f, "results"), **(datasets(f, "series") if "series" in f else {})}
                self.assertEqual(sorted(stored), sorted(expected), archive)
                for path, c in expected.items():
                    d = stored[path]
                    where = f"{os.path.basename(archive)}:{path}"
                    self.assertEqual(text(d.attrs["units"]), c["units"], where)
                    self.assertEqual(text(d.attrs["description"]), c["description"], where)
                    if c.get("axis"):
                        self.assertEqual(d.shape, (c["samples"],), where)
                        times = d[...]
                        self.assertEqual((times[0], times[-1]), (c["first_s"], c["last_s"]), where)
                        continue
                    self.assertEqual(d.shape[1:], () if c["width"] == 1 else (c["width"],), where)
                    if c["type"] == "complex128":
                        self.assertEqual(d.dtype.names, ("re", "im"), where)
                    else:
                        self.assertEqual((d.dtype.kind, d.dtype.itemsize), H5_KINDS[c["type"]], where)
                    self.assertEqual(text(d.attrs.get("levels", [])), c["levels"], where)
                    self.assertEqual(text(d.attrs.get("component_names", [])), c["component_names"], where)
                    self.assertEqual(text(d.attrs.get("time_axis", "")), c["time_axis"], where)
                    fill = d.attrs.get("fill")
                    self.assertEqual(None if fill is None else int(fill), c["fill"], where)
                # The bookkeeping and design datasets, as the manifest describes them.
                for c in self.manifest["runs"]:
                    d = f[c["path"]]
                    self.assertEqual(text(d.attrs["units"]), c["units"], c["path"])
                    self.assertEqual(text(d.attrs["description"]), c["description"], c["path"])
                    self.assertEqual(text(d.attrs.get("levels", [])), c["levels"], c["path"])
                design = {c["path"]: c for c in self.manifest["design"]}
                for path, d in datasets(f, "design").items():
                    self.assertIn(path, design)
                    self.assertEqual(text(d.attrs["units"]), design[path]["units"], path)
                    self.assertEqual(text(d.attrs["description"]), design[path]["description"], path)
                    self.assertEqual(text(d.attrs.get("levels", [])), design[path]["levels"], path)
        self.assertEqual(seen, set(analyses), "the test studies run every analysis of the manifest")

    def test_run_status_levels_are_the_archives(self):
        # The manifest's run_status (name, code) against what a real archive stores: /runs/status's
        # levels name code i at position i, and the root counters the writer keeps (runs_ok,
        # runs_failed, runs_pending) count the statuses with those codes.
        levels = self.manifest["run_status"]
        self.assertEqual(sorted(e["name"] for e in levels), ["failed", "ok", "pending"])
        code = {e["name"]: e["code"] for e in levels}
        for archive in self.archives:
            with h5py.File(archive, "r") as f:
                stored = text(f["runs/status"].attrs["levels"])
                self.assertEqual({name: stored.index(name) for name in stored}, code, archive)
                status = f["runs/status"][...]
                for name in ("ok", "failed", "pending"):
                    self.assertEqual(int((status == code[name]).sum()), int(f.attrs["runs_" + name]),
                                     f"{archive}: runs_{name}")
                self.assertGreater(int((status == code["ok"]).sum()), 0, archive)

    def test_roles_follow_the_rule(self):
        # A rating is an int8 column whose levels begin "level 1"; the one named "level" is overall.
        for analysis in self.manifest["analyses"]:
            for c in analysis["columns"]:
                rated = c["type"] == "int8" and c["levels"][:1] and c["levels"][0].lower() == "level 1"
                role = ("overall_rating" if c["name"] == "level" else "rating") if rated else ""
                self.assertEqual(c["role"], role, c["path"])
        fq = {c["name"]: c["role"] for c in next(a for a in self.manifest["analyses"]
                                                   if a["name"] == "flying_qualities")["columns"]}
        self.assertEqual((fq["level"], fq["phugoid_level"], fq["short_period_level"]),
                         ("overall_rating", "rating", "rating"))

    def test_text_table_names_every_path(self):
        out = gesweep("columns")
        self.assertEqual(out.returncode, 0, out.stderr)
        printed = {line.split()[0] for line in out.stdout.splitlines() if line and not line.startswith("#")}
        paths = {c["path"] for c in self.manifest["runs"] + self.manifest["design"]}
        for analysis in self.manifest["analyses"]:
            paths |= {c["path"] for c in analysis["columns"]} | {a["path"] for a in analysis["time_axes"]}
        self.assertEqual(paths - printed, set())

    def test_a_script_that_gesweep_starts_asks_that_gesweep(self):
        # scripts/lib/columns.py, with neither GESWEEP_BINARY nor GESWEEP_COLUMNS_MANIFEST set, in a
        # script that `gesweep report` starts (GESWEEP_REPORT_SCRIPT): the manifest is that binary's.
        script = os.path.join(self.work.name, "where.py")
        with open(script, "w") as f:
            f.write(f"import sys\nsys.path.insert(0, {os.path.join(ROOT, 'scripts', 'lib')!r})\nimport columns\n"
                    "print(columns.where())\nprint(','.join(columns.analyses()))\n")
        env = {k: v for k, v in os.environ.items() if k not in ("GESWEEP_BINARY", "GESWEEP_COLUMNS_MANIFEST")}
        env["GESWEEP_REPORT_SCRIPT"] = script
        out = subprocess.run([GESWEEP, "report", self.archives[0], "-o", os.path.join(self.work.name, "r")],
                             capture_output=True, text=True, timeout=120, cwd=ROOT, env=env)
        self.assertEqual(out.returncode, 0, out.stderr)
        where, names = out.stdout.splitlines()
        self.assertEqual(where, f"`{os.path.realpath(GESWEEP)} columns --json`")
        self.assertEqual(names.split(","), [a["name"] for a in self.manifest["analyses"]])

    def test_bad_aircraft_is_one_line(self):
        missing = os.path.join(tempfile.gettempdir(), "no_such_aircraft_for_gesweep_columns.toml")
        out = gesweep("columns", "--aircraft", missing)
        self.assertEqual(out.returncode, 2, out.stderr)
        self.assertEqual(len(out.stderr.strip().splitlines()), 1, out.stderr)
        self.assertIn(missing, out.stderr)
        self.assertEqual(out.stdout, "")


if __name__ == "__main__":
    unittest.main(verbosity=2)
