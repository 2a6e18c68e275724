#!/usr/bin/python3
"""End-to-end checks of `gesweep land` (issue 4): the JSON shape {run, summary, series}, the summary's
unit-suffixed fields, the CSV series, and the error contract (one line on stderr, exit code 2).

Oracles: the issue's acceptance numbers (landed, sink rate < 1.5 m/s from 500 m at 52.21 m/s) and the
glide-path kinematics (the reference descends at u0·γ)."""
import csv
import io
import json
import math
import subprocess
import sys
import unittest

GESWEEP = sys.argv.pop(1)
ANCE = "studies/aircraft/ance.toml"


def run(*args):
    return subprocess.run([GESWEEP, "land", "--aircraft", ANCE, *args], capture_output=True, text=True, timeout=120)


class Land(unittest.TestCase):
    def test_json_summary_and_series(self):
        out = run("--start-height-m", "500", "--speed-mps", "52.21", "--glide-slope-deg", "2.5", "--format", "json",
                  "--output-dt-s", "1")
        self.assertEqual(out.returncode, 0, out.stderr)
        doc = json.loads(out.stdout)
        self.assertEqual(set(doc), {"run", "summary", "series"})
        s = doc["summary"]
        self.assertEqual(s["outcome"], "landed")
        self.assertGreater(s["touchdown_sink_rate_mps"], 0.0)
        self.assertLess(s["touchdown_sink_rate_mps"], 1.5)
        for key in ("touchdown_time_s", "touchdown_distance_past_transmitter_m", "touchdown_pitch_deg",
                    "touchdown_speed_mps", "max_abs_elevator_deg", "max_abs_pitch_rate_degps", "saturated_time_s",
                    "glide_path_error_at_flare_m", "flare_start_time_s"):
            self.assertIsInstance(s[key], float, key)
        self.assertEqual(s["design"]["status"], "ok")
        self.assertEqual(len(s["design"]["gain"]), 9)
        self.assertEqual(s["design"]["gain"]["delta_h"], 0.0)
        self.assertTrue(all(re < 0 for re, _ in s["design"]["closed_loop_eigenvalues_per_s"]))
        series = doc["series"]
        n = len(series["time_s"])
        self.assertGreater(n, 200)
        self.assertTrue(all(len(column) == n for column in series.values()))
        self.assertEqual(series["phase"][0], "glide_slope")
        self.assertEqual(series["phase"][-1], "flare")
        # The glide path's reference height: 500 − u0·γ·t.
        sink = 52.21 * math.radians(2.5)
        for t, ref, phase in zip(series["time_s"], series["reference_height_m"], series["phase"]):
            if phase == "glide_slope":
                self.assertAlmostEqual(ref, 500.0 - sink * t, places=6)

    def test_without_h_derivatives_and_options_are_reported(self):
        out = run("--no-h-derivatives", "--flare-height-m", "8", "--tau-s", "4", "--q-weights", "1,1,1,1,1,1,1,1,1",
                  "--r-weight", "1", "--format", "json", "--summary-only")
        self.assertEqual(out.returncode, 0, out.stderr)
        doc = json.loads(out.stdout)
        self.assertFalse(doc["run"]["h_derivatives"])
        self.assertEqual(doc["run"]["flare_height_m"], 8.0)
        self.assertEqual(doc["run"]["flare_time_constant_s"], 4.0)
        self.assertIsNone(doc["series"])
        self.assertIn(doc["summary"]["outcome"], {"landed", "no_touchdown", "stall", "diverged"})

    def test_csv_series(self):
        out = run("--output-dt-s", "5")
        self.assertEqual(out.returncode, 0, out.stderr)
        rows = list(csv.DictReader(io.StringIO(out.stdout)))
        self.assertGreater(len(rows), 40)
        self.assertIn("elevator_rad", rows[0])  # SI, as the archive's series/landing/ (LandingSample::DescribeSeries)
        self.assertEqual(rows[0]["phase"], "glide_slope")
        self.assertAlmostEqual(float(rows[-1]["height_m"]), 0.788, places=6)

    def test_csv_summary_row(self):
        out = run("--summary-only")
        self.assertEqual(out.returncode, 0, out.stderr)
        rows = list(csv.DictReader(io.StringIO(out.stdout)))
        self.assertEqual(len(rows), 1)
        self.assertEqual(rows[0]["outcome"], "landed")

    def test_bad_input_is_one_line_exit_2(self):
        for args, flag in ((["--q-weights", "1,2,3"], "--q-weights"), (["--r-weight", "0"], "--r-weight"),
                           (["--tau-s", "-1"], "--tau-s"), (["--format", "xml"], "--format"),
                           (["--plant-height-reference", "ground"], "--plant-height-reference"),
                           (["--speed-mps", "10"], "--speed-mps")):
            out = run(*args)
            self.assertEqual(out.returncode, 2, args)
            self.assertEqual(out.stdout, "", args)
            self.assertEqual(len(out.stderr.strip().splitlines()), 1, out.stderr)
            self.assertIn(flag, out.stderr)

    def test_csv_summary_columns_and_json_keys_unchanged(self):
        """The summary's columns come from LandingResult's description: the CSV header and the JSON keys
        are those `gesweep land` wrote before, in the same order."""
        header = ("outcome,touchdown_time_s,touchdown_distance_past_transmitter_m,touchdown_sink_rate_mps,"
                  "touchdown_pitch_deg,touchdown_speed_mps,flare_start_time_s,glide_path_error_at_flare_m,"
                  "max_abs_elevator_deg,max_abs_elevator_command_deg,max_abs_pitch_rate_degps,saturated_time_s,"
                  "longest_saturation_s,min_speed_mps,max_speed_mps,final_time_s,final_height_m,"
                  "touchdown_airspeed_mps,flare_max_abs_elevator_deg,flare_max_abs_pitch_rate_degps,steps,"
                  "rejected_steps,rhs_calls")
        out = run("--summary-only")
        self.assertEqual(out.stdout.splitlines()[0], header)
        doc = json.loads(run("--summary-only", "--format", "json").stdout)
        self.assertEqual(list(doc["summary"]), header.split(",")[:1] + ["message"] + header.split(",")[1:] + ["design"])
        for key in ("aircraft", "start_height_m", "start_speed_mps", "start_pitch_deg", "start_glide_path_offset_m",
                    "glide_slope_deg", "flare_height_m", "flare_time_constant_s", "q_weights", "r_weight",
                    "actuator_pole_per_s", "compensator_pole_per_s", "elevator_min_deg", "elevator_max_deg",
                    "plant_height_reference", "h_derivatives", "cdh", "interpolation", "integrator",
                    "flare_asymptote_m", "reset_compensator_at_flare", "rtol", "atol", "max_step_s", "time_limit_s",
                    "wind_20ft_mps", "wind_shear", "turbulence", "turbulence_sigma_w_mps",
                    "turbulence_sample_interval_s", "pitch_rate_gust", "gust_axis", "gust_amplitude_mps",
                    "gust_half_length_m", "gust_start_s", "seed", "run_index", "turbulent_integrator"):
            self.assertIn(key, doc["run"])
        self.assertEqual(doc["run"]["integrator"], "dopri5")
        self.assertEqual(doc["run"]["turbulence_sigma_w_mps"], 0.0)  # σ_w in force: no turbulence

    def test_older_flag_names_are_aliases(self):
        """Each flag whose name is not its key's (--speed-mps for start_speed_mps, ...) still works, and
        gives what the key's own flag gives."""
        older = ["--speed-mps", "55", "--start-offset-m", "2", "--tau-s", "5", "--plant-height-reference", "fixed",
                 "--plant-reference-height-m", "12", "--rtol", "1e-4", "--atol", "1e-7", "--output-dt-s", "4",
                 "--format", "json"]
        keys = ["--start-speed-mps", "55", "--start-glide-path-offset-m", "2", "--flare-time-constant-s", "5",
                "--plant-height-reference", "fixed", "--plant-fixed-reference-height-m", "12",
                "--relative-tolerance", "1e-4", "--absolute-tolerance", "1e-7", "--output-interval-s", "4",
                "--format", "json"]
        a, b = run(*older), run(*keys)
        self.assertEqual(a.returncode, 0, a.stderr)
        self.assertEqual(a.stdout, b.stdout)
        doc = json.loads(a.stdout)
        self.assertEqual(doc["run"]["start_speed_mps"], 55.0)
        self.assertEqual(doc["run"]["plant_reference_height_m"], 12.0)
        self.assertEqual(doc["run"]["rtol"], 1e-4)
        self.assertEqual(doc["series"]["time_s"][1], 4.0)
        # The error names the flag as typed.
        self.assertIn("--tau-s = -1", run("--tau-s", "-1").stderr)
        self.assertIn("--flare-time-constant-s = -1", run("--flare-time-constant-s", "-1").stderr)
        # --output-dt-s and --summary-only exclude each other, under either name.
        self.assertEqual(run("--output-dt-s", "1", "--summary-only").returncode, 2)
        self.assertEqual(run("--output-interval-s", "1", "--summary-only").returncode, 2)

    def test_design_failure_exit_3(self):
        out = run("--q-weights", "0,0,0,0,0,0,0,0,0", "--summary-only", "--format", "json")
        self.assertEqual(out.returncode, 3, out.stderr)
        doc = json.loads(out.stdout)
        self.assertEqual(doc["summary"]["outcome"], "design_failed")
        self.assertEqual(doc["summary"]["design"]["status"], "not_detectable")


if __name__ == "__main__":
    unittest.main()
