#!/usr/bin/python3
"""End-to-end checks of `gesweep modes` and `gesweep boundary` (issue 2's "done when"), and of the
request flags of `run`, `merge` and `query`.

The oracles: the paper's boundary bracket (between its rows H/b = 0.4 and 0.578), the JSON shape
the issue specifies, and the error contract (one line on stderr, exit code 2)."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

GESWEEP = sys.argv.pop(1)
ANCE = "studies/aircraft/ance.toml"


def run(*args):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=60)


class Boundary(unittest.TestCase):
    def test_paper_speed_boundary_between_rows(self):
        out = run("boundary", "--aircraft", ANCE, "--speed-mps", "32.0208", "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        b = json.loads(out.stdout)["boundaries"][0]
        self.assertGreater(b["height_m"], 2.0748)
        self.assertLess(b["height_m"], 2.9987)
        self.assertGreater(b["height_over_span"], 0.4)
        self.assertLess(b["height_over_span"], 0.5781)

    def test_no_boundary_without_h_derivatives(self):
        out = run("boundary", "--aircraft", ANCE, "--speed-mps", "32.0208", "--no-h-derivatives", "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        b = json.loads(out.stdout)["boundaries"][0]
        self.assertIsNone(b["height_m"])
        self.assertIn("stable", b["reason"])

    def test_speed_range(self):
        out = run("boundary", "--aircraft", ANCE, "--speeds-mps", "30:50:3", "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        speeds = [b["speed_mps"] for b in json.loads(out.stdout)["boundaries"]]
        self.assertEqual(speeds, [30.0, 40.0, 50.0])

    # The scanned range (BoundaryOptions::Describe: --lower-height-m, --upper-height-m). Oracle: the
    # paper's bracket above, 2.0748 m < H* < 2.9987 m at this speed.
    def test_scanned_range_flags(self):
        def boundary(*flags):
            out = run("boundary", "--aircraft", ANCE, "--speed-mps", "32.0208", "--format", "json", *flags)
            self.assertEqual(out.returncode, 0, out.stderr)
            return json.loads(out.stdout)["boundaries"][0]

        full = boundary()
        around = boundary("--lower-height-m", "2.0", "--upper-height-m", "3.0", "--tolerance-m", "1e-6")
        self.assertEqual(around["scanned_range_m"], [2.0, 3.0])
        self.assertGreater(around["height_m"], 2.0748)
        self.assertLess(around["height_m"], 2.9987)
        # The same root, whatever the range around it: both are refined to rounding (hurwitz).
        self.assertAlmostEqual(around["height_m"], full["height_m"], delta=1e-6)
        above = boundary("--lower-height-m", "3.0")
        self.assertEqual(above["scanned_range_m"][0], 3.0)
        self.assertIsNone(above["height_m"])
        below = boundary("--upper-height-m", "2.0")
        self.assertEqual(below["scanned_range_m"][1], 2.0)
        self.assertIsNone(below["height_m"])


class Modes(unittest.TestCase):
    def test_table_heights_json_shape(self):
        out = run("modes", "--aircraft", ANCE, "--speed-mps", "32.0208", "--table-heights", "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        rows = json.loads(out.stdout)["rows"]
        self.assertEqual(len(rows), 12)  # 11 finite rows + free flight
        self.assertEqual(rows[-1]["height_m"], "inf")
        for row in rows:
            self.assertEqual(len(row["eigenvalues"]), 5)
            for mode in ("short_period", "phugoid", "height"):
                self.assertTrue({"re", "im", "natural_frequency_radps", "damping_ratio"} <= set(row["modes"][mode]))
            self.assertEqual(row["stable"], row["stability_margin_per_s"] < 0)
        # The paper: unstable at and below H/b = 0.5 (2.5935 m), stable above.
        by_height = {r["height_m"]: r["stable"] for r in rows}
        self.assertFalse(by_height[2.0748])
        self.assertTrue(by_height[2.9987])
        self.assertTrue(by_height[5.5922])

    def test_table_and_csv_formats(self):
        table = run("modes", "--aircraft", ANCE, "--speed-mps", "32.0208", "--table-heights")
        self.assertEqual(table.returncode, 0, table.stderr)
        self.assertIn("short period", table.stdout)
        csv = run("modes", "--aircraft", ANCE, "--speed-mps", "32.0208", "--heights-m", "1,2,inf", "--format", "csv")
        self.assertEqual(csv.returncode, 0, csv.stderr)
        lines = csv.stdout.strip().splitlines()
        self.assertEqual(len(lines), 4)
        self.assertTrue(lines[0].startswith("height_m,height_over_span,"))


class BadInput(unittest.TestCase):
    CASES = [
        (("modes", "--aircraft", "no/such/file.toml", "--speed-mps", "30", "--table-heights"), "no/such/file.toml"),
        (("modes", "--aircraft", ANCE, "--speed-mps", "-3", "--table-heights"), "--speed-mps"),
        (("modes", "--aircraft", ANCE, "--speed-mps", "0", "--table-heights"),
         "--speed-mps = 0: expected a number in [1, 300] m/s"),
        (("modes", "--aircraft", ANCE, "--speed-mps", "30", "--heights-m", "1,abc"), "'abc'"),
        (("modes", "--aircraft", ANCE, "--speed-mps", "30", "--heights-m", "0.5"), "wheel-contact"),
        (("modes", "--aircraft", ANCE, "--speed-mps", "30", "--heights-m", "1", "--cdh", "cubic"), "--cdh"),
        (("modes", "--aircraft", ANCE, "--speed-mps", "30", "--heights-m", "1", "--format", "xml"), "--format"),
        (("modes", "--aircraft", ANCE, "--speed-mps", "30"), "--heights-m"),
        (("boundary", "--aircraft", ANCE), "--speed-mps"),
        (("boundary", "--aircraft", ANCE, "--speeds-mps", "30:40:5:1"), "a:b:n"),
        (("boundary", "--aircraft", ANCE, "--speeds-mps", "40:30"), "a < b"),
        (("boundary", "--aircraft", ANCE, "--speed-mps", "30", "--method", "dense"), "--method"),
        (("boundary", "--aircraft", ANCE, "--speed-mps", "nan"), "--speed-mps"),
        (("boundary", "--aircraft", ANCE, "--speed-mps", "30", "--lower-height-m", "0.1"),
         "--lower-height-m = 0.1: expected a height >= the wheel-contact height 0.788 m"),
        (("boundary", "--aircraft", ANCE, "--speed-mps", "30", "--lower-height-m", "5", "--upper-height-m", "3"),
         "--upper-height-m = 3: expected more than --lower-height-m = 5 m"),
        (("boundary", "--aircraft", ANCE, "--speed-mps", "30", "--lower-height-m", "50"),
         "--lower-height-m = 50: expected less than --upper-height-m = 13.373 m"),
        (("boundary", "--aircraft", ANCE, "--speed-mps", "30", "--tolerance-m", "1"),
         "--tolerance-m = 1: expected a number in [1e-09, 0.001] m"),
        (("boundary", "--archive", "no/such.h5", "--tolerance-m", "1e-5"), "--tolerance-m"),
        (("modes", "--aircraft", "README.md", "--speed-mps", "30", "--table-heights"), "README.md"),
        (("nosuchcommand",), "nosuchcommand"),
    ]

    def test_each_bad_input_gives_one_line_and_exit_2(self):
        for args, fragment in self.CASES:
            with self.subTest(args=args):
                out = run(*args)
                self.assertEqual(out.returncode, 2, out.stderr)
                lines = out.stderr.strip().splitlines()
                self.assertEqual(len(lines), 1, out.stderr)
                self.assertIn(fragment, lines[0])
                self.assertEqual(out.stdout, "")


class RequestFlags(unittest.TestCase):
    """The request flags of run, merge and query (engine/cli): the described switches and numbers
    reach the request, a short name is shown with its flag, and a flag left out is told apart from
    one given with the default's value."""

    STUDY = "tests/report/flying_qualities_small.toml"  # 240 quick runs

    @classmethod
    def setUpClass(cls):
        cls.directory = tempfile.TemporaryDirectory()
        cls.archive = os.path.join(cls.directory.name, "small.h5")
        out = run("run", cls.STUDY, "-o", cls.archive, "-q")
        assert out.returncode == 0, out.stderr

    @classmethod
    def tearDownClass(cls):
        cls.directory.cleanup()

    def test_quiet_has_its_short_name_in_the_help(self):
        for command in ("run", "merge"):
            with self.subTest(command=command):
                self.assertIn("-q,--quiet", run(command, "--help").stdout)

    def test_the_dry_run_budget_given_is_the_one_used(self):
        out = run("run", self.STUDY, "--dry-run", "--format", "json", "--dry-run-budget-s", "0.25")
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertEqual(json.loads(out.stdout)["budget_seconds"], 0.25)

    def test_an_aggregate_query_takes_memory_and_group_limits(self):
        out = run("query", self.archive, "--group-by", "status", "--aggregate", "count", "--memory-mb", "1",
                  "--max-groups", "1", "--format", "json")
        self.assertEqual(out.returncode, 0, out.stderr)
        # The study's 4 x 60 grid, every run ok: one group, within --max-groups 1.
        self.assertEqual(json.loads(out.stdout)["rows"], [{"count": 4 * 60, "status": "ok"}])

    def test_each_bad_request_flag_gives_one_line_and_exit_2(self):
        output = os.path.join(self.directory.name, "never.h5")
        existing = os.path.join(self.directory.name, "existing.h5")
        open(existing, "w").close()
        cases = [
            (("run", self.STUDY, "-o", output, "--threads", "0"), "--threads = 0"),
            (("run", self.STUDY, "-o", output, "--threads", "4097"), "--threads = 4097"),
            (("run", self.STUDY, "-o", output, "--dry-run-budget-s", "0"), "--dry-run-budget-s = 0"),
            (("run", self.STUDY, "-o", output, "--ranks-per-node", "2"), "only with --mpi"),
            (("merge", self.archive, "-o", existing), "already exists; pass --force"),
            (("query", self.archive, "--memory-mb", "256"), "--memory-mb"),
            (("query", self.archive, "--max-groups", "1000000"), "--max-groups"),
            (("query", self.archive, "--group-by", "status", "--memory-mb", "0"), "--memory-mb = 0"),
            (("query", self.archive, "--group-by", "status", "--max-groups", "0"), "--max-groups = 0"),
        ]
        for args, fragment in cases:
            with self.subTest(args=args):
                out = run(*args)
                self.assertEqual(out.returncode, 2, out.stderr)
                lines = out.stderr.strip().splitlines()
                self.assertEqual(len(lines), 1, out.stderr)
                self.assertIn(fragment, lines[0])
        self.assertFalse(os.path.exists(output))


if __name__ == "__main__":
    unittest.main(verbosity=2)
