#!/usr/bin/python3
"""Renamed run parameters (docs/sweep.md, "Renamed parameters"): a study written with the older names
(flare_tau_s, lqr.r, lqr.q_<state>) still runs, with one note line on stderr per older name, and gives
the archive of the same study written with today's names: the same results and run ids, the design
columns under today's names. A study that gives one parameter under both names is refused (one line,
exit 2). An archive written before the rename (its attributes name the older names) is still read:
`gesweep boundary --archive` rebuilds its runs' models as from today's archive.

The oracle is the same study written with today's names: nothing about the run may differ but the
note."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np

GESWEEP = sys.argv.pop(1)
ANCE = os.path.abspath("studies/aircraft/ance.toml")

STUDY = """format_version = 1
name = "renamed"
aircraft = "{aircraft}"

[analyses.landing]

[parameters]
height_m = 100.0
speed_mps = 52.21
{flare} = 3.0
{r} = 2.0
{q_delta_h} = 5.0

[design]
kind = "grid"
[[design.parameter]]
name = "{q_delta_u}"
values = [1.0, 4.0]
"""

OLDER = {"flare": "flare_tau_s", "r": "lqr.r", "q_delta_h": "lqr.q_delta_h", "q_delta_u": "lqr.q_delta_u"}
TODAY = {"flare": "flare_time_constant_s", "r": "r_weight", "q_delta_h": "q_weights.delta_h",
         "q_delta_u": "q_weights.delta_u"}


def run(*args):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=120)


class RenamedParameters(unittest.TestCase):
    def setUp(self):
        self.directory = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.directory.cleanup()

    def sweep(self, names, tag):
        study = os.path.join(self.directory.name, f"{tag}.toml")
        with open(study, "w") as f:
            f.write(STUDY.format(aircraft=ANCE, **names))
        archive = os.path.join(self.directory.name, f"{tag}.h5")
        out = run("run", study, "-o", archive, "--quiet")
        self.assertEqual(out.returncode, 0, out.stderr)
        return study, archive, out.stderr

    def test_older_names_run_as_today_with_a_note_each(self):
        older_study, older, stderr = self.sweep(OLDER, "older")
        _, today, today_stderr = self.sweep(TODAY, "today")
        self.assertNotIn("note", today_stderr)
        notes = [line for line in stderr.splitlines() if line.startswith("gesweep: note: ")]
        self.assertEqual(len(notes), 4, stderr)
        for key in ("flare", "r", "q_delta_h", "q_delta_u"):
            mine = [line for line in notes if f"'{OLDER[key]}' is now '{TODAY[key]}'" in line]
            self.assertEqual(len(mine), 1, f"{OLDER[key]}: {stderr}")
            self.assertIn(older_study, mine[0])
        with h5py.File(older, "r") as a, h5py.File(today, "r") as b:
            self.assertIn("design/q_weights.delta_u", a)
            self.assertNotIn("design/lqr.q_delta_u", a)
            np.testing.assert_array_equal(a["design/q_weights.delta_u"][()], [1.0, 4.0])
            np.testing.assert_array_equal(a["runs/id"][()], b["runs/id"][()])
            np.testing.assert_array_equal(a["runs/status"][()], b["runs/status"][()])
            for name in ("touchdown_time_s", "touchdown_sink_rate_mps"):
                np.testing.assert_array_equal(a[f"results/landing/{name}"][()], b[f"results/landing/{name}"][()])
            # The two weights give two landings.
            self.assertNotEqual(*a["results/landing/touchdown_time_s"][()])

    def test_one_parameter_under_both_names_is_refused(self):
        study = os.path.join(self.directory.name, "both.toml")
        with open(study, "w") as f:
            f.write(STUDY.format(aircraft=ANCE, **TODAY).replace("[design]", "lqr.r = 3.0\n\n[design]"))
        out = run("run", study, "--dry-run")
        self.assertEqual(out.returncode, 2, out.stderr)
        errors = [line for line in out.stderr.splitlines() if line.startswith("gesweep: error: ")]
        self.assertEqual(len(errors), 1, out.stderr)
        self.assertIn("expected one value of r_weight", errors[0])
        self.assertIn(study, errors[0])

    def test_an_archive_with_the_older_names_is_read(self):
        study = os.path.join(self.directory.name, "map.toml")
        with open(study, "w") as f:
            f.write(STUDY.format(aircraft=ANCE, **TODAY).replace("[analyses.landing]", "[analyses.modes]\n[analyses.landing]")
                    .replace("height_m = 100.0\n", "flare_height_m = 0.9\n")
                    .replace('name = "q_weights.delta_u"\nvalues = [1.0, 4.0]',
                             'name = "height_m"\nlinspace = [1.0, 6.0, 11]'))
        today = os.path.join(self.directory.name, "today.h5")
        out = run("run", study, "-o", today, "--quiet")
        self.assertEqual(out.returncode, 0, out.stderr)
        older = os.path.join(self.directory.name, "older.h5")
        with open(today, "rb") as source, open(older, "wb") as target:
            target.write(source.read())
        back = {today_name: OLDER[key] for key, today_name in TODAY.items()}
        with h5py.File(older, "r+") as f:
            attributes = f["design"].attrs
            names = [n.decode() if isinstance(n, bytes) else n for n in attributes["unswept_parameter_names"]]
            self.assertIn("r_weight", names)
            dtype = attributes["unswept_parameter_names"].dtype
            del attributes["unswept_parameter_names"]
            attributes.create("unswept_parameter_names", [back.get(n, n) for n in names], dtype=dtype)
        boundaries = []
        for archive in (today, older):
            out = run("boundary", "--archive", archive, "--format", "json")
            self.assertEqual(out.returncode, 0, out.stderr)
            boundaries.append(json.loads(out.stdout)["boundaries"])
        self.assertEqual(boundaries[0], boundaries[1])
        self.assertTrue(all(b["height_m"] is not None for b in boundaries[0]))


if __name__ == "__main__":
    unittest.main()
