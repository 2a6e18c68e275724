#!/usr/bin/python3
"""End-to-end checks of `gesweep boundary --sensitivities` (issue 7, local sensitivities).

Oracles: the JSON shape the issue asks for; p·dH*/dp = value × dH/dp; the ranking by |p·dH*/dp|;
and dH*/du0 against the binary's own boundary at two neighbouring speeds (a central difference of H*
itself, not of anything the sensitivity code computes)."""
import json
import subprocess
import sys
import unittest

GESWEEP = sys.argv.pop(1)
ANCE = "studies/aircraft/ance.toml"
SPEED = 32.0208
# Speed step of the H*(u0) central difference: H* moves ~0.06 m, so the 1e-4 m root tolerance of
# `gesweep boundary` costs ~0.2 %, and the curvature of H*(u0) over ±0.5 m/s about as much.
SPEED_STEP = 0.5
SPEED_AGREEMENT = 0.01  # relative


def run(*args):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=120)


def boundary_json(*extra):
    out = run("boundary", "--aircraft", ANCE, "--format", "json", *extra)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)["boundaries"]


class BoundarySensitivities(unittest.TestCase):
    def test_json_shape_ranking_and_relative_form(self):
        b = boundary_json("--speed-mps", str(SPEED), "--sensitivities")[0]
        self.assertEqual(b["sensitivity_mode"], "phugoid")
        self.assertLess(b["dsigma_dH_per_s_per_m"], 0.0)
        rows = b["sensitivities"]
        names = [r["parameter"] for r in rows]
        for expected in ("scale.CLh", "scale.CMh", "scale.CMalphadot", "scale.CMalpha", "scale.CLalpha",
                         "scale.CMq", "scale.CDh", "scale.CDo", "mass_kg", "pitch_inertia_kgm2", "speed_mps"):
            self.assertIn(expected, names)
        self.assertIn("scale.CMde", b["no_effect_parameters"])
        magnitudes = [abs(r["p_dH_dp_m"]) for r in rows]
        self.assertEqual(magnitudes, sorted(magnitudes, reverse=True))
        for r in rows:
            self.assertAlmostEqual(r["p_dH_dp_m"], r["value"] * r["dH_dp"], delta=1e-12 * max(1.0, abs(r["p_dH_dp_m"])))
            self.assertIn(r["dH_dp_unit"], ("m", "m/kg", "m/(kg m^2)", "m/(m/s)"))
        clh = rows[names.index("scale.CLh")]
        self.assertGreater(clh["dH_dp"], 0.0)  # a stronger CLh raises the boundary (tests/modal)

    def test_speed_sensitivity_matches_boundaries_at_neighbouring_speeds(self):
        b = boundary_json("--speed-mps", str(SPEED), "--sensitivities")[0]
        analytic = next(r for r in b["sensitivities"] if r["parameter"] == "speed_mps")["dH_dp"]
        hi, lo = boundary_json("--speeds-mps", f"{SPEED + SPEED_STEP},{SPEED - SPEED_STEP}")
        central = (hi["height_m"] - lo["height_m"]) / (2 * SPEED_STEP)
        self.assertAlmostEqual(analytic, central, delta=SPEED_AGREEMENT * abs(central))

    def test_no_boundary_gives_empty_list_and_reason(self):
        b = boundary_json("--speed-mps", str(SPEED), "--sensitivities", "--no-h-derivatives")[0]
        self.assertEqual(b["sensitivities"], [])
        self.assertIn("no boundary", b["sensitivities_reason"])

    def test_table_lists_ranked_parameters(self):
        out = run("boundary", "--aircraft", ANCE, "--speed-mps", str(SPEED), "--sensitivities")
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("ranked by |p dH*/dp|", out.stdout)
        self.assertIn("scale.CLh", out.stdout)
        self.assertIn("not in Eq. (1), no effect:", out.stdout)

    def test_csv_is_refused_with_one_line(self):
        out = run("boundary", "--aircraft", ANCE, "--speed-mps", str(SPEED), "--sensitivities", "--format", "csv")
        self.assertEqual(out.returncode, 2)
        self.assertEqual(out.stdout, "")
        self.assertEqual(len(out.stderr.strip().splitlines()), 1)
        self.assertIn("--sensitivities", out.stderr)


if __name__ == "__main__":
    unittest.main()
