#!/usr/bin/python3
"""End-to-end tests of `gesweep query` and `gesweep boundary --archive` (issue 6).

Oracles, none from the code under test:
  - query results against direct h5py reads of the same archive, selected and sorted with numpy;
  - the boundary extracted from a sweep against `gesweep boundary --aircraft` (FindBoundary on the
    aircraft file, the engine core's direct root finding) to 1 mm, and against the sweep's own
    per-run boundary analysis;
  - an archive read while a sweep writes it, and after the sweep is killed: every row the query
    returns is a complete run whose design values are the grid's (computed here with numpy) and whose
    margin is finite; writing into it is refused ("archive in use", "stopped without closing it").
Run by ctest (tests/query/CMakeLists.txt) with the gesweep binary as the first argument.
"""
import csv
import fcntl
import io
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import h5py
import numpy as np

GESWEEP = os.path.abspath(sys.argv.pop(1))
HERE = os.path.dirname(os.path.abspath(__file__))
ANCE = "studies/aircraft/ance.toml"
# The accuracy for the refined boundary.
BOUNDARY_AGREEMENT_M = 1e-3
# Design values the engine computes (linspace) against numpy's: a few ulps.
GRID_RELATIVE_TOLERANCE = 1e-12
WORK = tempfile.mkdtemp(prefix="gesweep_query_cli_")
GRID = os.path.join(WORK, "grid.h5")


def run(*args, timeout=120):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=timeout)


def setUpModule():
    out = run("run", os.path.join(HERE, "boundary_grid.toml"), "-o", GRID, "-q")
    assert out.returncode == 0, out.stderr


def tearDownModule():
    shutil.rmtree(WORK, ignore_errors=True)


def read(path, name):
    with h5py.File(path, "r") as f:
        dataset = f[name]
        values = dataset[...]
        if dataset.dtype.kind in "iu" and "fill" in dataset.attrs:
            values = values.astype(float)
            values[values == dataset.attrs["fill"]] = math.nan
        return values


def csv_rows(text):
    return list(csv.DictReader(io.StringIO(text)))


def same(a, b):
    return (math.isnan(a) and math.isnan(b)) or a == b


class QueryAgainstH5py(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.height = read(GRID, "design/height_m")
        cls.speed = read(GRID, "design/speed_mps")
        cls.h_derivatives = read(GRID, "design/h_derivatives")
        cls.sigma = read(GRID, "results/modes/stability_margin_per_s")
        cls.boundary = read(GRID, "results/boundary/height_m")
        cls.crossings = read(GRID, "results/boundary/crossing_count")
        cls.status = read(GRID, "runs/status")
        with h5py.File(GRID, "r") as f:
            cls.message = [m.decode() for m in f["runs/message"][...]]

    def test_selections_and_values_equal_h5py(self):
        columns = "index,speed_mps,height_m,h_derivatives,stability_margin_per_s,boundary/height_m,crossing_count,message"
        cases = [
            ("height_m < 3 and stability_margin_per_s > 0", (self.height < 3) & (self.sigma > 0)),
            ("h_derivatives and speed_mps >= 32.0208", (self.h_derivatives == 1) & (self.speed >= 32.0208)),
            ("not h_derivatives or isnan(boundary/height_m)", (self.h_derivatives == 0) | np.isnan(self.boundary)),
            ("(speed_mps == 25 or speed_mps == 60) and height_m > 10", ((self.speed == 25) | (self.speed == 60))
             & (self.height > 10)),
            ("boundary/height_m / height_m > 1.5", self.boundary / self.height > 1.5),
            ("message != \"\" and status == \"ok\"", np.array([m != "" for m in self.message]) & (self.status == 1)),
            ("crossing_count >= 1", self.crossings >= 1),
        ]
        for where, mask in cases:
            with self.subTest(where=where):
                out = run("query", GRID, "--where", where, "--columns", columns, "--format", "csv")
                self.assertEqual(out.returncode, 0, out.stderr)
                rows = csv_rows(out.stdout)
                expected = np.nonzero(mask)[0]
                self.assertGreater(len(expected), 0, "a vacuous case")
                self.assertEqual([int(r["index"]) for r in rows], expected.tolist())
                for r in rows:
                    i = int(r["index"])
                    self.assertEqual(float(r["speed_mps"]), self.speed[i])
                    self.assertEqual(float(r["height_m"]), self.height[i])  # CSV numbers are exact
                    self.assertEqual(r["h_derivatives"], "true" if self.h_derivatives[i] == 1 else "false")
                    self.assertTrue(same(float(r["stability_margin_per_s"]), self.sigma[i]))
                    self.assertTrue(same(float(r["boundary/height_m"]), self.boundary[i]))
                    self.assertEqual(int(r["crossing_count"]), self.crossings[i])
                    self.assertEqual(r["message"], self.message[i])

    def test_sorted_top_rows_equal_numpy(self):
        for flags, order in ((["--descending"], np.argsort(-self.sigma, kind="stable")),
                             ([], np.argsort(self.sigma, kind="stable"))):
            out = run("query", GRID, "--sort", "stability_margin_per_s", *flags, "--limit", "7", "--format", "json",
                      "--columns", "index,stability_margin_per_s")
            self.assertEqual(out.returncode, 0, out.stderr)
            result = json.loads(out.stdout)
            self.assertEqual([r["index"] for r in result["rows"]], order[:7].tolist())
            self.assertEqual([r["stability_margin_per_s"] for r in result["rows"]], self.sigma[order[:7]].tolist())
            self.assertEqual(result["matched"], len(self.sigma))
            self.assertEqual(result["shown"], 7)
            self.assertFalse(result["snapshot"])
        # NaN sorts last whichever the direction.
        out = run("query", GRID, "--sort", "boundary/height_m", "--format", "csv", "--columns", "boundary/height_m")
        values = [float(r["boundary/height_m"]) for r in csv_rows(out.stdout)]
        finite = [v for v in values if not math.isnan(v)]
        self.assertEqual(finite, sorted(self.boundary[np.isfinite(self.boundary)].tolist()))
        self.assertTrue(all(math.isnan(v) for v in values[len(finite):]))

    def test_describe_counts_units_and_provenance(self):
        out = run("query", GRID, "--describe", "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        d = json.loads(out.stdout)
        counts = np.bincount(self.status, minlength=3)
        self.assertEqual(d["status"], {"pending": int(counts[0]), "ok": int(counts[1]), "failed": int(counts[2])})
        with h5py.File(GRID, "r") as f:
            for column in d["columns"]:
                self.assertEqual(column["units"], f[column["path"]].attrs["units"], column["path"])
            self.assertEqual(d["provenance"]["study_name"], f.attrs["study_name"])
            self.assertEqual(d["provenance"]["git_commit"], f.attrs["git_commit"])
        names = {c["name"]: c["path"] for c in d["columns"]}
        self.assertEqual(names["height_m"], "design/height_m")
        self.assertEqual(names["boundary/height_m"], "results/boundary/height_m")
        self.assertIn("results/modes/eigenvalues", [o["path"] for o in d["other_datasets"]])
        table = run("query", GRID, "--describe")
        self.assertEqual(table.returncode, 0, table.stderr)
        self.assertIn("400 ok, 0 failed, 0 pending", table.stdout)

    def test_bad_input_is_one_line_and_exit_2(self):
        cases = [
            (["--where", "heigth_m < 3"], "at column 1: unknown column 'heigth_m' (did you mean height_m?)"),
            (["--where", "height_m < 3 and (speed_mps > 3"], "at column 32: expected ')'"),
            (["--where", 'status == "faild"'], 'at column 11: "faild" is not a level of status'),
            (["--columns", "height_m,damping_ratio"], "ambiguous column 'damping_ratio'"),
            (["--sort", "eigenvalues"], "not a per-run scalar column"),
            (["--format", "xml"], "expected table, csv or json"),
            (["--limit", "-5"], "--limit = -5: expected a whole number in [0, 9007199254740992]"),
            (["--describe", "--where", "height_m > 1"], "takes no --where"),
        ]
        for args, says in cases:
            with self.subTest(args=args):
                out = run("query", GRID, *args)
                self.assertEqual(out.returncode, 2, out.stdout + out.stderr)
                self.assertEqual(out.stdout, "")
                lines = out.stderr.strip().splitlines()
                self.assertEqual(len(lines), 1, out.stderr)
                self.assertTrue(lines[0].startswith("gesweep: error: "), lines[0])
                self.assertIn(says, lines[0])
        for path, says in ((os.path.join(WORK, "missing.h5"), "no such archive"),
                           (os.path.join(HERE, "boundary_grid.toml"), "not an HDF5 file")):
            out = run("query", path)
            self.assertEqual(out.returncode, 2)
            self.assertIn(says, out.stderr)


class BoundaryFromArchive(unittest.TestCase):
    def direct(self, speeds, h_derivatives):
        args = ["boundary", "--aircraft", ANCE, "--speeds-mps", ",".join(repr(s) for s in speeds), "--format", "json"]
        if not h_derivatives:
            args.append("--no-h-derivatives")
        out = run(*args)
        self.assertEqual(out.returncode, 0, out.stderr)
        return {b["speed_mps"]: b["height_m"] for b in json.loads(out.stdout)["boundaries"]}

    def test_agrees_with_the_direct_root_finding_to_1_mm_and_is_written(self):
        archive = os.path.join(WORK, "boundary.h5")
        shutil.copy(GRID, archive)
        out = run("boundary", "--archive", archive, "--by", "speed_mps", "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        result = json.loads(out.stdout)
        self.assertTrue(result["written"])
        self.assertEqual(result["keys"], ["speed_mps", "h_derivatives"])
        points = result["boundaries"]
        self.assertEqual(len(points), 10)
        speeds = sorted({p["speed_mps"] for p in points})
        per_run = read(archive, "results/boundary/height_m")
        grid_speed = read(archive, "design/speed_mps")
        grid_h = read(archive, "design/h_derivatives")
        found = 0
        for on in (True, False):
            direct = self.direct(speeds, on)
            for p in points:
                if (p["h_derivatives"] == "true") != on:
                    continue
                expected = direct[p["speed_mps"]]
                with self.subTest(speed=p["speed_mps"], h_derivatives=on):
                    if expected is None:
                        self.assertIsNone(p["height_m"], p)
                        self.assertTrue(p["reason"])
                        continue
                    found += 1
                    self.assertLess(abs(p["height_m"] - expected), BOUNDARY_AGREEMENT_M)
                    self.assertLess(abs(p["height_over_span"] - expected / 5.187), BOUNDARY_AGREEMENT_M / 5.187)
                    # The sweep's per-run boundary analysis of the same model.
                    rows = np.nonzero((grid_speed == p["speed_mps"]) & (grid_h == (1 if on else 0)))[0]
                    self.assertLess(abs(p["height_m"] - per_run[rows[0]]), BOUNDARY_AGREEMENT_M)
                    self.assertLessEqual(p["grid_bracket_m"][0], p["height_m"])
                    self.assertGreaterEqual(p["grid_bracket_m"][1], p["height_m"])
        self.assertEqual(found, 4)  # with h-derivatives at 28, 32.0208, 45 and 60 m/s; none at 25
        with h5py.File(archive, "r") as f:
            group = f["analysis/boundary"]
            self.assertEqual(group["height_m"].attrs["units"], "m")
            self.assertEqual(group["speed_mps"].attrs["units"], "m/s")
            self.assertEqual(group["height_over_span"].attrs["units"], "1")
            for name in group:
                self.assertIn("description", group[name].attrs, name)
            self.assertEqual(list(group.attrs["keys"]), ["speed_mps", "h_derivatives"])
            stored = group["height_m"][...]
            printed = np.array([math.nan if p["height_m"] is None else p["height_m"] for p in points])
            np.testing.assert_array_equal(stored, printed)
            self.assertEqual(group["speed_mps"][...].tolist(), [p["speed_mps"] for p in points])
        self.assertFalse(os.path.exists(archive + ".lock"))

    def test_refused_while_a_sweep_holds_the_archive(self):
        archive = os.path.join(WORK, "locked.h5")
        shutil.copy(GRID, archive)
        with open(archive + ".lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # what `gesweep run` holds while it writes
            out = run("boundary", "--archive", archive)
            self.assertEqual(out.returncode, 2, out.stdout)
            self.assertIn("archive in use", out.stderr)
            self.assertEqual(len(out.stderr.strip().splitlines()), 1)
            with h5py.File(archive, "r") as f:
                self.assertNotIn("analysis/boundary", f)
            printed = run("boundary", "--archive", archive, "--no-write", "--format", "csv")
            self.assertEqual(printed.returncode, 0, printed.stderr)
        os.remove(archive + ".lock")

    def test_bad_input(self):
        cases = [
            (["--archive", GRID, "--by", "height_m", "--no-write"], "--by names the other swept parameters"),
            (["--archive", GRID, "--by", "mass_kg", "--no-write"], "(h_derivatives, speed_mps)"),
            (["--archive", GRID, "--cdh", "zero"], "the model of --archive comes from the archive's runs"),
            (["--archive", GRID, "--aircraft", ANCE], "excludes"),
            (["--by", "speed_mps", "--aircraft", ANCE, "--speed-mps", "30"], "only with --archive"),
            ([], "--aircraft or --archive"),
        ]
        for args, says in cases:
            with self.subTest(args=args):
                out = run("boundary", *args)
                self.assertEqual(out.returncode, 2, out.stdout + out.stderr)
                self.assertIn(says, out.stderr)


def grid_values(study_speed, study_height, index):
    """Design values of run `index` of the long sweep: speed outer, height inner (C order)."""
    speeds = np.linspace(*study_speed)
    heights = np.linspace(*study_height)
    return speeds[index // len(heights)], heights[index % len(heights)]


class ReadWhileASweepWrites(unittest.TestCase):
    SPEED = (28.0, 60.0, 2000)
    HEIGHT = (0.79, 14.0, 1000)

    def check_rows(self, text):
        result = json.loads(text)
        self.assertEqual(result["shown"], result["matched"])
        for row in result["rows"]:
            self.assertEqual(row["status"], "ok")
            speed, height = grid_values(self.SPEED, self.HEIGHT, row["index"])
            self.assertLess(abs(row["speed_mps"] - speed), GRID_RELATIVE_TOLERANCE * speed)
            self.assertLess(abs(row["height_m"] - height), GRID_RELATIVE_TOLERANCE * height)
            self.assertIsNotNone(row["stability_margin_per_s"])  # finite (JSON null otherwise)
        return result

    def test_snapshot_while_writing_and_after_a_kill(self):
        archive = os.path.join(WORK, "long.h5")
        sweep = subprocess.Popen([GESWEEP, "run", os.path.join(HERE, "long_sweep.toml"), "-o", archive, "--threads",
                                  "1", "-q"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            deadline = time.time() + 120
            complete = 0
            while time.time() < deadline and complete == 0:
                time.sleep(0.1)
                self.assertIsNone(sweep.poll(), "the sweep ended before it could be read mid-way")
                try:
                    with h5py.File(archive, "r", swmr=True) as f:
                        complete = int(np.count_nonzero(f["runs/status"][...]))
                except (OSError, KeyError):
                    continue
            self.assertGreater(complete, 0, "no batch written in time")
            columns = "index,speed_mps,height_m,stability_margin_per_s,status"
            out = run("query", archive, "--columns", columns, "--format", "json")
            print(f"\n  mid-sweep query: exit {out.returncode}, {complete} runs complete when polled",
                  file=sys.stderr)
            if out.returncode == 0:
                result = self.check_rows(out.stdout)
                self.assertTrue(result["snapshot"])
                self.assertGreaterEqual(result["complete"], complete)
            else:
                self.assertEqual(out.returncode, 2, out.stderr)
                self.assertIn("archive in use", out.stderr)
            writing = run("boundary", "--archive", archive)
            self.assertEqual(writing.returncode, 2, writing.stdout)
            self.assertIn("archive in use", writing.stderr)
            self.assertIsNone(sweep.poll(), "the sweep ended before it was killed")
        finally:
            sweep.send_signal(signal.SIGKILL)
            sweep.wait()
        out = run("query", archive, "--columns", columns, "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        result = self.check_rows(out.stdout)
        self.assertTrue(result["snapshot"])
        self.assertGreater(result["complete"], 0)
        self.assertLess(result["complete"], result["runs"])
        with h5py.File(archive, "r", swmr=True) as f:
            self.assertEqual(result["complete"], int(np.count_nonzero(f["runs/status"][...])))
        describe = run("query", archive, "--describe")
        self.assertIn("snapshot", describe.stdout)
        refused = run("boundary", "--archive", archive)
        self.assertEqual(refused.returncode, 2)
        self.assertIn("stopped without closing it", refused.stderr)
        printed = run("boundary", "--archive", archive, "--no-write", "--format", "json")
        self.assertEqual(printed.returncode, 0, printed.stderr)
        self.assertTrue(json.loads(printed.stdout)["snapshot"])


if __name__ == "__main__":
    unittest.main(verbosity=2)
