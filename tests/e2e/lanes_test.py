#!/usr/bin/python3
"""Open-loop runs flown in SIMD lanes by `gesweep run --lanes W` (docs/sweep.md, "Lanes").

The oracle is the archive of the same study run one at a time (`--lanes 1`, one thread): the path
the runner took before lanes. Every dataset of every other archive -- widths 1, 2, 4 and 8 on one
and two threads, two shards merged (virtually and by copy) -- must equal it byte for byte: design
values, run ids, statuses, messages of the failed runs, every result column and, in a second study
that stores them, the time series. The study mixes runs that touch down, stall and reach the time
limit, two models, and failed runs (with a mass of 1e-300 the state is not finite after the first
step). Then rows of a lanes-flown archive are replayed one at a time by `gesweep simulate --run-index
I`, whose summary must equal the row to the bit. (The amplitudes -6 and 3 degrees are ones whose
conversion to radians differs in the last bit between x * pi / 180, which the sweep's adapter used
until 2026-12-07, and x * (pi / 180), simulate's flag's: both now use the latter.) A width the lanes
do not have is refused with one line, exit 2.

Turbulent landings (SimulateLandingBatch) likewise: a study of 36 short landings from 32 m in Dryden
turbulence (three winds, one of them 0 m/s, which is still air and flown by dopri5 one at a time inside
the batch; three speeds, two slopes, with and without h-derivatives), its archive at every width on
one and two threads against `--lanes 1`, its series too, and rows of a lanes-flown archive replayed by
`gesweep land --seed S --run-index I`, whose summary (and gain) must equal the row to the bit.

Usage: lanes_test.py BUILD/gesweep
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
ANCE_MASS_KG = 182.055  # studies/aircraft/ance.toml

STUDY = """format_version = 1
name = "lanes"
aircraft = "{aircraft}"

[analyses.modes]

[analyses.open_loop]
input = "step"
duration_s = 12.0
integrator = "rk4"
step_s = 0.015

[output]
chunk_runs = 32
{output}

[design]
kind = "grid"
[[design.parameter]]
name = "h_derivatives"
values = [true, false]
[[design.parameter]]
name = "mass_kg"
values = [{mass}, 1e-300]
[[design.parameter]]
name = "speed_mps"
values = [25.2, 27.0, 34.0]
[[design.parameter]]
name = "height_m"
values = [1.3, 4.0, 13.0]
[[design.parameter]]
name = "pulse_amplitude_deg"
values = [-6.0, 0.5, 3.0]
"""

LANDING_STUDY = """format_version = 1
name = "landing_lanes"
aircraft = "{aircraft}"

[analyses.landing]
time_limit_s = 40.0

[parameters]
height_m = 32.0
turbulence = "dryden"
seed = 7

[output]
chunk_runs = 16
{output}

[design]
kind = "grid"
[[design.parameter]]
name = "h_derivatives"
values = [true, false]
[[design.parameter]]
name = "wind_20ft_mps"
values = [-7.717, 0.0, -15.433]
[[design.parameter]]
name = "speed_mps"
values = [45.0, 52.21, 58.0]
[[design.parameter]]
name = "glide_slope_deg"
values = [2.5, 3.2]
"""

LANDING_SUMMARY_STUDY = LANDING_STUDY.format(aircraft=ANCE, output="")
LANDING_SERIES_STUDY = LANDING_STUDY.format(aircraft=ANCE, output="time_series = true\noutput_dt_s = 0.1")

SUMMARY_STUDY = STUDY.format(aircraft=ANCE, mass=ANCE_MASS_KG, output="")
SERIES_STUDY = STUDY.format(aircraft=ANCE, mass=ANCE_MASS_KG, output="time_series = true\noutput_dt_s = 0.1")


def gesweep(*args, expect=0):
    out = subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=300)
    if out.returncode != expect:
        raise AssertionError(f"gesweep {' '.join(args)}: exit {out.returncode}, expected {expect}: {out.stderr}")
    return out


def datasets(path):
    """Every dataset of an archive: path -> (dtype, shape, bytes)."""
    found = {}
    with h5py.File(path, "r") as f:
        def visit(name, item):
            if isinstance(item, h5py.Dataset):
                values = item[()]
                found[name] = (str(item.dtype), item.shape, np.asarray(values).tobytes())
        f.visititems(visit)
    return found


class Lanes(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.studies = {}
        for name, text in (("summary", SUMMARY_STUDY), ("series", SERIES_STUDY), ("landing", LANDING_SUMMARY_STUDY),
                           ("landing_series", LANDING_SERIES_STUDY)):
            path = os.path.join(cls.dir, name + ".toml")
            with open(path, "w") as f:
                f.write(text)
            cls.studies[name] = path

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_study(self, study, archive, *flags):
        path = os.path.join(self.dir, archive)
        # Exit 3: the runs of mass 1e-300 fail (their status and messages are compared too); the
        # landings all succeed.
        gesweep("run", self.studies[study], "-o", path, "--quiet", *flags,
                expect=0 if study.startswith("landing") else 3)
        return path

    def oracle(self, study):
        return datasets(self.run_study(study, study + "-oracle.h5", "--lanes", "1", "--threads", "1"))

    def assert_same(self, expected, path, what):
        got = datasets(path)
        self.assertEqual(sorted(got), sorted(expected), what)
        for name, (dtype, shape, data) in expected.items():
            self.assertEqual(got[name][:2], (dtype, shape), f"{what}: {name}")
            self.assertTrue(got[name][2] == data, f"{what}: {name} differs")

    def test_every_width_thread_count_and_sharding_writes_the_same_archive(self):
        expected = self.oracle("summary")
        self.assertIn("results/open_loop/end_event", expected)
        with h5py.File(os.path.join(self.dir, "summary-oracle.h5"), "r") as f:
            events = set(f["results/open_loop/end_event"][:].tolist())
            levels = [str(v, "utf-8") if isinstance(v, bytes) else str(v)
                      for v in f["results/open_loop/end_event"].attrs["levels"]]
            status = f["runs/status"][:]
            messages = [m.decode() for m in f["runs/message"][status == 2]]
        # The runs end in every way a lane ends (besides divergence), and some fail with messages.
        self.assertTrue({levels.index(e) for e in ("touchdown", "stall", "time_limit")} <= events, events)
        self.assertEqual(int((status == 2).sum()), len(status) // 2)
        self.assertTrue(all("open_loop: the state became non-finite" in m for m in messages), messages[:3])
        for lanes in ("1", "2", "4", "8"):
            for threads in ("1", "2"):
                path = self.run_study("summary", f"w{lanes}t{threads}.h5", "--lanes", lanes, "--threads", threads)
                self.assert_same(expected, path, f"--lanes {lanes} --threads {threads}")
        shards = [self.run_study("summary", f"shard{i}.h5", "--lanes", "8", "--threads", "2", "--shard", f"{i}/2")
                  for i in range(2)]
        for kind in ("virtual", "copy"):
            merged = os.path.join(self.dir, f"merged-{kind}.h5")
            gesweep("merge", *shards, "-o", merged, "--quiet", *(["--copy"] if kind == "copy" else []))
            self.assert_same(expected, merged, f"two shards at --lanes 8, merged ({kind})")

    def test_time_series_are_the_same_in_lanes(self):
        expected = self.oracle("series")
        self.assertIn("series/open_loop/height_m", expected)
        for lanes in ("2", "8"):
            path = self.run_study("series", f"series-w{lanes}.h5", "--lanes", lanes, "--threads", "2")
            self.assert_same(expected, path, f"series, --lanes {lanes}")

    def test_a_row_flown_in_lanes_replays_alone_to_the_bit(self):
        archive = self.run_study("summary", "replay.h5", "--lanes", "8", "--threads", "2")
        with h5py.File(archive, "r") as f:
            index = f["runs/index"][:]
            design = {k: f["design/" + k][:] for k in f["design"]}
            # The group also links the design's columns (the netCDF view's coordinates): not results.
            results = {k: f["results/open_loop/" + k][:] for k in f["results/open_loop"] if k not in f["design"]}
            levels = [str(v, "utf-8") if isinstance(v, bytes) else str(v)
                      for v in f["results/open_loop/end_event"].attrs["levels"]]
        rows = [r for r in range(len(index)) if design["mass_kg"][r] == ANCE_MASS_KG]
        self.assertEqual(len(rows), len(index) // 2)
        compared = 0
        for row in rows[::3]:
            flags = ["simulate", "--aircraft", ANCE, "--height-m", repr(float(design["height_m"][row])),
                     "--speed-mps", repr(float(design["speed_mps"][row])), "--input", "step",
                     "--pulse-amplitude-deg", repr(float(design["pulse_amplitude_deg"][row])),
                     "--duration-s", "12", "--integrator", "rk4", "--step-s", "0.015",
                     "--seed", "0", "--run-index", str(int(index[row])), "--summary-only", "--format", "json"]
            if not design["h_derivatives"][row]:
                flags.append("--no-h-derivatives")
            summary = json.loads(gesweep(*flags).stdout)["summary"]
            state = dict(zip(summary["final_state_names"], summary["final_state"]))
            for key, column in results.items():
                if key in summary:
                    value = levels.index(summary[key]) if key == "end_event" else summary[key]
                else:  # final_delta_w_mps, ...: a component of the final state
                    value = state[key[len("final_"):]]
                self.assertEqual(value, column[row], f"row {row}: {key}")
                compared += 1
        self.assertEqual(compared, len(results) * len(rows[::3]))
        self.assertGreaterEqual(len(results), 12)

    def test_turbulent_landings_write_the_same_archive_in_lanes(self):
        expected = self.oracle("landing")
        with h5py.File(os.path.join(self.dir, "landing-oracle.h5"), "r") as f:
            steps = f["results/landing/accepted_steps"][:]
            outcome = f["results/landing/outcome"][:]
            wind = f["design/wind_20ft_mps"][:]
        # Landings that end at different steps, all touching down, the still-air ones among them.
        self.assertEqual(len(steps), 36)
        self.assertEqual(set(outcome.tolist()), {0})
        self.assertGreater(len(set(steps[wind != 0].tolist())), 20)
        for lanes in ("1", "2", "4", "8"):
            for threads in ("1", "2"):
                if lanes == "1" and threads == "1":
                    continue
                path = self.run_study("landing", f"landing-w{lanes}t{threads}.h5", "--lanes", lanes,
                                      "--threads", threads)
                self.assert_same(expected, path, f"landing, --lanes {lanes} --threads {threads}")

    def test_turbulent_landing_series_are_the_same_in_lanes(self):
        expected = self.oracle("landing_series")
        self.assertIn("series/landing/height_m", expected)
        self.assertIn("series/landing/w_g_mps", expected)
        path = self.run_study("landing_series", "landing-series-w8.h5", "--lanes", "8", "--threads", "2")
        self.assert_same(expected, path, "landing series, --lanes 8")

    def test_a_landing_flown_in_lanes_replays_alone_to_the_bit(self):
        archive = self.run_study("landing", "landing-replay.h5", "--lanes", "8", "--threads", "2")
        with h5py.File(archive, "r") as f:
            index = f["runs/index"][:]
            design = {k: f["design/" + k][:] for k in f["design"]}
            results = {k: f["results/landing/" + k][:] for k in f["results/landing"] if k not in f["design"]}
            levels = [str(v, "utf-8") if isinstance(v, bytes) else str(v)
                      for v in f["results/landing/outcome"].attrs["levels"]]
        compared = 0
        for row in range(0, len(index), 5):
            flags = ["land", "--aircraft", ANCE, "--start-height-m", "32", "--time-limit-s", "40",
                     "--speed-mps", repr(float(design["speed_mps"][row])),
                     "--glide-slope-deg", repr(float(design["glide_slope_deg"][row])),
                     "--wind-20ft-mps", repr(float(design["wind_20ft_mps"][row])), "--turbulence", "dryden",
                     "--seed", "7", "--run-index", str(int(index[row])), "--summary-only", "--format", "json"]
            if not design["h_derivatives"][row]:
                flags.append("--no-h-derivatives")
            document = json.loads(gesweep(*flags).stdout)
            summary = dict(document["summary"])
            summary.update({k: v for k, v in document["run"].items() if k not in summary})
            summary.update({k: v for k, v in summary.get("design", {}).items() if k not in summary})
            summary["accepted_steps"] = summary.get("steps")
            # The design's largest closed-loop real part: land gives the eigenvalues ([re, im] each).
            summary["closed_loop_max_real_per_s"] = max(e[0] for e in summary["design"]["closed_loop_eigenvalues_per_s"])
            for key, column in results.items():
                self.assertIn(key, summary, f"row {row}: {key} is not in land's JSON")
                value = summary[key]
                if key == "outcome":
                    value = levels.index(value)
                if key == "gain":  # by state name, in Eq. (14)'s order
                    self.assertEqual(list(value.values()), list(column[row]), f"row {row}: gain")
                elif value is None:  # NaN in JSON
                    self.assertTrue(np.isnan(column[row]), f"row {row}: {key}")
                else:
                    self.assertEqual(value, column[row], f"row {row}: {key}")
                compared += 1
        self.assertGreaterEqual(compared, 8 * 20)

    def test_a_width_the_lanes_do_not_have_is_refused_with_one_line(self):
        for lanes in ("3", "0", "16"):
            out = gesweep("run", self.studies["summary"], "-o", os.path.join(self.dir, "bad.h5"), "--lanes", lanes,
                          expect=2)
            self.assertEqual(len(out.stderr.strip().splitlines()), 1, out.stderr)
            self.assertIn("--lanes", out.stderr)
            self.assertFalse(os.path.exists(os.path.join(self.dir, "bad.h5")))


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
