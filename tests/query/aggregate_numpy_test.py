#!/usr/bin/python3
"""`gesweep query` aggregates and the --where additions through the real binary (issue 19, and
issue 13's parser limits), against oracles that are not the code under test:

  - --group-by/--aggregate (table, CSV, JSON) against NumPy's nan-functions (nansum, nanmin, nanmax,
    nanmean, nanstd with ddof 0 and 1, nanmedian, nanquantile with its default "linear" method) on the
    same archive read with h5py; the exact medians and quantiles also under a 1 MB budget that forces
    further passes over a 72,000-run archive;
  - `in`, `%`, `contains`, `matches` against numpy.isin, numpy's % and Python's re on the columns;
  - column wildcards against the datasets h5py lists;
  - the deeply nested expressions that crashed the reader: exit 2, one short line.
Run by ctest (tests/query/CMakeLists.txt) with the gesweep binary as the first argument.
"""
import csv
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
import warnings

import h5py
import numpy as np

GESWEEP = os.path.abspath(sys.argv.pop(1))
HERE = os.path.dirname(os.path.abspath(__file__))
WORK = tempfile.mkdtemp(prefix="gesweep_aggregate_numpy_")
GRID = os.path.join(WORK, "grid.h5")
LARGE = os.path.join(WORK, "large.h5")
# Means, sums and standard deviations: NumPy sums pairwise, the engine streams (compensated sum,
# Welford's update); both are within a few ulps of the values' scale on 400 or 72,000 runs.
MOMENT_RELATIVE = 1e-12
# A refusal of a 125,000-character expression echoes only its start: the line stays short.
LONGEST_MESSAGE = 400

LARGE_STUDY = """format_version = 1
name = "aggregate_large"
aircraft = "{aircraft}"
[analyses.modes]
[output]
chunk_runs = 4096
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [26.0, 60.0, 12]
[[design.parameter]]
name = "height_m"
logspace = [0.79, 14.0, 6000]
"""


def run(*args, timeout=120):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=timeout)


def setUpModule():
    out = run("run", os.path.join(HERE, "boundary_grid.toml"), "-o", GRID, "-q")
    assert out.returncode == 0, out.stderr
    study = os.path.join(WORK, "large.toml")
    with open(study, "w") as f:
        f.write(LARGE_STUDY.format(aircraft=os.path.abspath("studies/aircraft/ance.toml")))
    out = run("run", study, "-o", LARGE, "-q")
    assert out.returncode == 0, out.stderr


def tearDownModule():
    shutil.rmtree(WORK, ignore_errors=True)


def column(path, name):
    """A per-run column as h5py reads it; integer fill values and levels as the engine reads them."""
    with h5py.File(path, "r") as f:
        dataset = f[name]
        values = dataset[...]
        if dataset.dtype.kind in "iu":
            values = values.astype(float)
            if "fill" in dataset.attrs:
                values[values == dataset.attrs["fill"]] = math.nan
        elif dataset.dtype.kind in "SOU":
            values = np.array([v.decode() if isinstance(v, bytes) else str(v) for v in values], dtype=object)
        return values


def query_json(*args):
    out = run("query", *args, "--format", "json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def missing(value):
    return value is None or (isinstance(value, float) and math.isnan(value))


def same(a, b):
    """Exact equality, a missing value (JSON null, an empty CSV cell read as None) standing for NaN."""
    if missing(a) or missing(b):
        return missing(a) and missing(b)
    return a == b


def near(a, b):
    if missing(a) or missing(b):
        return missing(a) and missing(b)
    return abs(a - b) <= MOMENT_RELATIVE * max(1.0, abs(b))


def numpy_statistics(values):
    """The engine's statistics by NumPy's nan-functions (NaN skipped; None where NumPy gives nan)."""
    finite = values[~np.isnan(values)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN groups: NumPy warns and gives nan
        return {
            "count": int(finite.size),
            "sum": float(np.nansum(values)),
            "min": float(np.nanmin(values)) if finite.size else math.nan,
            "max": float(np.nanmax(values)) if finite.size else math.nan,
            "mean": float(np.nanmean(values)),
            "std": float(np.nanstd(values, ddof=1)) if finite.size > 1 else math.nan,
            "std0": float(np.nanstd(values, ddof=0)),
            "median": float(np.nanmedian(values)),
            "q05": float(np.nanquantile(values, 0.05)),
            "q95": float(np.nanquantile(values, 0.95)),
        }


STATISTICS = "count({c}),sum({c}),min({c}),max({c}),mean({c}),std({c}),std({c}, 0),median({c})," \
             "quantile({c}, 0.05),quantile({c}, 0.95)"
LABELS = ["count({c})", "sum({c})", "min({c})", "max({c})", "mean({c})", "std({c})", "std({c}, 0)",
          "median({c})", "quantile({c}, 0.05)", "quantile({c}, 0.95)"]
KEYS = ["count", "sum", "min", "max", "mean", "std", "std0", "median", "q05", "q95"]
EXACT = {"count", "min", "max", "median", "q05", "q95"}


class GroupedAggregatesAgainstNumPy(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.h = column(GRID, "design/h_derivatives")
        cls.speed = column(GRID, "design/speed_mps")
        cls.columns = {"boundary/height_m": column(GRID, "results/boundary/height_m"),
                       "stability_margin_per_s": column(GRID, "results/modes/stability_margin_per_s")}
        cls.aggregate = "count," + ",".join(STATISTICS.format(c=c) for c in cls.columns)

    def check_rows(self, rows, names):
        keys = sorted(set(zip(self.h, self.speed)))
        self.assertEqual(len(rows), len(keys))  # 2 x 5 groups, in ascending key order
        some_missing = False
        for row, (h, speed) in zip(rows, keys):
            self.assertEqual(row["h_derivatives"], "true" if h == 1 else "false")
            self.assertEqual(row["speed_mps"], speed)
            members = (self.h == h) & (self.speed == speed)
            self.assertEqual(row["count"], int(members.sum()))
            for c, values in self.columns.items():
                expected = numpy_statistics(values[members])
                some_missing = some_missing or expected["count"] < members.sum()
                for label, key in zip(LABELS, KEYS):
                    got = row[names[label.format(c=c)]]
                    check = same if key in EXACT else near
                    self.assertTrue(check(got, expected[key]),
                                    f"{label.format(c=c)} of h_derivatives={h}, speed={speed}: "
                                    f"gesweep {got!r}, NumPy {expected[key]!r}")
        self.assertTrue(some_missing, "no group has missing values: the NaN skipping went untested")

    def test_json_equals_numpy(self):
        out = query_json(GRID, "--group-by", "h_derivatives,speed_mps", "--aggregate", self.aggregate)
        names = {c["name"]: c["name"] for c in out["columns"]}
        self.assertEqual([c["name"] for c in out["columns"]][:3], ["h_derivatives", "speed_mps", "count"])
        self.assertEqual(out["groups"], 10)
        self.assertEqual(out["matched"], 400)
        self.assertEqual(out["passes"], 1)
        statistic = {c["name"]: c.get("statistic") for c in out["columns"]}
        self.assertEqual(statistic["quantile(stability_margin_per_s, 0.95)"], "quantile")
        self.check_rows(out["rows"], names)

    def test_csv_equals_numpy_and_the_table_counts(self):
        out = run("query", GRID, "--group-by", "h_derivatives,speed_mps", "--aggregate", self.aggregate,
                  "--format", "csv")
        self.assertEqual(out.returncode, 0, out.stderr)
        rows = list(csv.DictReader(io.StringIO(out.stdout)))

        def value(text):
            if text in ("true", "false"):
                return text
            number = float(text)
            return None if math.isnan(number) else number

        rows = [{k: value(v) for k, v in row.items()} for row in rows]
        self.check_rows(rows, {name: name for name in rows[0]})
        table = run("query", GRID, "--group-by", "speed_mps", "--aggregate", "count,median(height_m)")
        self.assertEqual(table.returncode, 0, table.stderr)
        lines = table.stdout.splitlines()
        self.assertEqual(lines[0].split(), ["speed_mps", "count", "median(height_m)"])
        self.assertEqual(len(lines), 1 + 5 + 1)
        self.assertTrue(lines[-1].startswith("# 5 shown of 5 groups of 400 matching runs (400 complete of 400)"),
                        lines[-1])

    def test_where_filters_runs_before_grouping(self):
        out = query_json(GRID, "--where", "stability_margin_per_s > 0", "--group-by", "speed_mps",
                         "--aggregate", "count,max(height_m)")
        sigma = self.columns["stability_margin_per_s"]
        height = column(GRID, "design/height_m")
        unstable = sigma > 0
        expected = {s: (int(np.sum(unstable & (self.speed == s))),
                        float(np.max(height[unstable & (self.speed == s)])))
                    for s in np.unique(self.speed[unstable])}
        self.assertEqual({r["speed_mps"]: (r["count"], r["max(height_m)"]) for r in out["rows"]}, expected)

    def test_without_group_by_one_row_of_every_run(self):
        out = query_json(GRID, "--aggregate", "count,mean(stable),quantile(boundary/height_m, 0.5)")
        stable = column(GRID, "results/modes/stable")
        self.assertEqual(len(out["rows"]), 1)
        row = out["rows"][0]
        self.assertEqual(row["count"], 400)
        self.assertTrue(near(row["mean(stable)"], float(np.mean(stable))))
        self.assertEqual(row["quantile(boundary/height_m, 0.5)"],
                         float(np.nanquantile(self.columns["boundary/height_m"], 0.5)))


class ExactOrderStatisticsInBoundedMemory(unittest.TestCase):
    def test_one_megabyte_budget_many_passes_same_exact_values(self):
        sigma = column(LARGE, "results/modes/stability_margin_per_s")
        height = column(LARGE, "design/height_m")
        speed = column(LARGE, "design/speed_mps")
        self.assertEqual(sigma.size, 72000)
        aggregate = ("median(stability_margin_per_s),quantile(stability_margin_per_s, 0.9),"
                     "quantile(stability_margin_per_s, 0.001),median(height_m),quantile(speed_mps, 0.3)")
        expected = [float(np.median(sigma)), float(np.quantile(sigma, 0.9)), float(np.quantile(sigma, 0.001)),
                    float(np.median(height)), float(np.quantile(speed, 0.3))]
        # 3 x 72,000 values x 16 bytes = 3.5 MB: one pass at the default 256 MB; a 1 MB budget holds
        # 65,536 values, less than one column, so the engine narrows each rank by histogram passes.
        for budget, more_passes in (("256", False), ("1", True)):
            out = query_json(LARGE, "--aggregate", aggregate, "--memory-mb", budget)
            row = out["rows"][0]
            got = [row[c["name"]] for c in out["columns"]]
            self.assertEqual(got, expected, f"--memory-mb {budget}")
            self.assertEqual(out["passes"] > 1, more_passes, out["passes"])
        grouped = query_json(LARGE, "--group-by", "speed_mps", "--aggregate", "median(stability_margin_per_s)",
                             "--memory-mb", "1")
        for row in grouped["rows"]:
            self.assertEqual(row["median(stability_margin_per_s)"],
                             float(np.median(sigma[speed == row["speed_mps"]])))


class WhereAdditionsAgainstPython(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.index = column(GRID, "runs/index")
        cls.speed = column(GRID, "design/speed_mps")
        cls.status = column(GRID, "runs/status")
        cls.message = column(GRID, "runs/message")
        cls.height = column(GRID, "design/height_m")

    def selected(self, where):
        out = query_json(GRID, "--where", where, "--columns", "index")
        return [row["index"] for row in out["rows"]]

    def expect(self, where, mask):
        self.assertEqual(self.selected(where), [int(i) for i in self.index[mask]], where)

    def test_remainder_in_contains_matches(self):
        self.expect("index % 7 == 3", self.index % 7 == 3)
        self.expect("(height_m * 1000) % 250 < 100", np.remainder(self.height * 1000, 250) < 100)
        self.expect("-index % 9 == 4", np.remainder(-self.index, 9) == 4)
        self.expect("speed_mps in (28, 60) and status in (\"ok\")",
                    np.isin(self.speed, [28, 60]) & (self.status == 1))
        self.expect("speed_mps not in (25, 32.0208)", ~np.isin(self.speed, [25, 32.0208]))
        has = np.array(["none" in m for m in self.message])
        self.assertTrue(has.any() and not has.all())
        self.expect("message contains \"none\"", has)
        self.expect("message not contains 'none'", ~has)
        pattern = r"^boundary: none \(.*stable"
        self.expect(f"message matches \"{pattern}\"", np.array([re.search(pattern, m) is not None
                                                               for m in self.message]))
        self.expect("message matches \"(?i)BOUNDARY\"",
                    np.array([re.search("(?i)BOUNDARY", m) is not None for m in self.message]))

    def test_column_wildcards(self):
        with h5py.File(GRID, "r") as f:
            runs = f["runs/status"].shape[0]
            per_run = []
            f.visititems(lambda name, o: per_run.append(name) if isinstance(o, h5py.Dataset)
                         and name.split("/")[0] in ("runs", "design", "results") and o.shape == (runs,)
                         and o.dtype.kind != "V" else None)
        phugoid = sorted(p for p in per_run if "/phugoid/" in p)
        self.assertGreaterEqual(len(phugoid), 2)
        out = query_json(GRID, "--columns", "phugoid/*", "--limit", "1")
        self.assertEqual(sorted(c["path"] for c in out["columns"]), phugoid)
        out = query_json(GRID, "--columns", "*", "--limit", "1")
        self.assertEqual(sorted(c["path"] for c in out["columns"]), sorted(per_run))
        self.assertEqual([c["path"] for c in out["columns"]][:2], ["runs/index", "design/h_derivatives"])
        out = query_json(GRID, "--columns", "speed_mps,*_m", "--limit", "1")
        paths = [c["path"] for c in out["columns"]]
        self.assertEqual(paths[0], "design/speed_mps")
        self.assertEqual(sorted(paths[1:]), sorted(p for p in per_run if p.endswith("_m")))


class RefusedInOneLine(unittest.TestCase):
    def refused(self, *args, fragment):
        out = run("query", GRID, *args)
        self.assertEqual(out.returncode, 2, out.stderr[:300])
        lines = out.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, out.stderr[:500])
        self.assertIn(fragment, lines[0])
        self.assertLess(len(lines[0]), LONGEST_MESSAGE, lines[0])
        self.assertEqual(out.stdout, "")

    def test_the_issues_crashing_expressions(self):
        for where in ("(" * 10000 + "height_m < 3" + ")" * 10000,
                      "abs(" * 25000 + "height_m" + ")" * 25000 + " < 3",
                      "-" * 120000 + "height_m < 3"):
            # "--where=..." keeps the command-line parser from reading "---..." as options.
            self.refused(f"--where={where}", fragment="nested deeper than 256 levels")

    def test_bad_aggregates_and_flag_combinations(self):
        self.refused("--aggregate", "quantile(height_m, 2)", fragment="expected a probability 0 <= p <= 1")
        self.refused("--aggregate", "mean(heigth_m)", fragment="did you mean height_m?")
        self.refused("--group-by", "phugiod/*", fragment="the pattern matches no column")
        self.refused("--aggregate", "count", "--columns", "height_m", fragment="--columns")
        self.refused("--memory-mb", "8", fragment="applies to --group-by/--aggregate only")
        self.refused("--group-by", "height_m", "--max-groups", "10", fragment="more than 10 groups")
        self.refused("--where", "message matches \"(\"", fragment="not a regular expression (RE2 syntax)")


if __name__ == "__main__":
    unittest.main(verbosity=2)
