#!/usr/bin/python3
"""Replay of a sweep's run alone (docs/disturbance.md, "Options, seeds and replay").

A sweep of turbulent open-loop responses and landings (two values of the seed parameter crossed with
two winds: four runs with run indices 0..3) is written by `gesweep run`; each run is then flown alone
by `gesweep simulate` / `gesweep land` with `--seed S --run-index I` and the run's parameters, and its
summary must equal the archived row to the bit: the turbulence is RunNoise(seed, run index), a
function of those two numbers only. A replay with another run index must differ (the test can fail).
The archive's air-motion series of a turbulent run are not all zero, and a still-air run's are.

Usage: replay_test.py BUILD/gesweep
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
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
ANCE = os.path.join(REPO, "studies", "aircraft", "ance.toml")

STUDY = """format_version = 1
name = "wind_replay"
aircraft = "{aircraft}"

[analyses.open_loop]
duration_s = 8.0
integrator = "rk4"
step_s = 0.01
input = "none"

[analyses.landing]
series_duration_s = 60.0

[parameters]
height_m = 40.0
speed_mps = 52.21
turbulence = "dryden"

[design]
kind = "grid"
[[design.parameter]]
name = "seed"
values = [5.0, 9.0]
[[design.parameter]]
name = "wind_20ft_mps"
values = [-7.717, 5.0]

[output]
time_series = true
output_dt_s = 0.05
"""


def run(*args):
    out = subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=300)
    if out.returncode != 0:
        raise AssertionError(f"gesweep {' '.join(args)}: exit {out.returncode}: {out.stderr}")
    return out.stdout


class Replay(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        study = os.path.join(cls.tmp.name, "study.toml")
        with open(study, "w") as f:
            f.write(STUDY.format(aircraft=ANCE))
        cls.archive = os.path.join(cls.tmp.name, "out.h5")
        run("run", study, "-o", cls.archive, "--quiet")
        with h5py.File(cls.archive, "r") as f:
            cls.index = f["runs/index"][:]
            cls.seed = f["design/seed"][:]
            cls.wind = f["design/wind_20ft_mps"][:]
            cls.open_loop = {k: f["results/open_loop/" + k][:] for k in ("end_time_s", "final_height_m",
                                                                          "final_speed_mps", "min_height_m")}
            cls.landing = {k: f["results/landing/" + k][:] for k in (
                "touchdown_time_s", "touchdown_distance_past_transmitter_m", "touchdown_sink_rate_mps",
                "touchdown_airspeed_mps", "flare_max_abs_elevator_deg")}
            cls.w_g = f["series/open_loop/w_g_mps"][:]

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def flags(self, row):
        return ["--aircraft", ANCE, "--turbulence", "dryden", "--wind-20ft-mps", repr(float(self.wind[row])),
                "--seed", str(int(self.seed[row])), "--summary-only", "--format", "json"]

    def simulate(self, row, run_index):
        return json.loads(run("simulate", "--height-m", "40", "--speed-mps", "52.21", "--duration-s", "8",
                              "--integrator", "rk4", "--step-s", "0.01", "--input", "none",
                              "--run-index", str(run_index), *self.flags(row)))["summary"]

    def land(self, row, run_index):
        return json.loads(run("land", "--start-height-m", "40", "--speed-mps", "52.21",
                              "--run-index", str(run_index), *self.flags(row)))["summary"]

    def test_open_loop_rows_replay_to_the_bit(self):
        self.assertEqual(len(self.seed), 4)
        for row in range(4):
            summary = self.simulate(row, int(self.index[row]))
            for key, column in self.open_loop.items():
                self.assertEqual(summary[key], column[row], f"run {row}: {key}")
        other = self.simulate(0, int(self.index[0]) + 1)
        self.assertNotEqual(other["final_height_m"], self.open_loop["final_height_m"][0])

    def test_landing_rows_replay_to_the_bit(self):
        for row in range(4):
            summary = self.land(row, int(self.index[row]))
            for key, column in self.landing.items():
                self.assertEqual(summary[key], column[row], f"run {row}: {key}")

    def test_air_motion_series_are_stored(self):
        finite = self.w_g[np.isfinite(self.w_g)]
        self.assertGreater(np.abs(finite).max(), 0.1, "turbulence in the stored w_g")


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
