#!/usr/bin/python3
"""The engine's eigen-analysis against the independent NumPy/SciPy peer (scripts/peer/gepeer.py).

Runs `gesweep modes --format json` and the peer on the same aircraft and options, and checks that
every eigenvalue agrees to kEigenvalueTolerance relative to max(1, |λ|), along with the mode
identification and σ: two speeds, with and without h-derivatives, linear and PCHIP, at the table
heights and free flight and at heights between the rows.

Usage: peer_modes_test.py --gesweep BUILD/gesweep [--aircraft studies/aircraft/ance.toml]
"""

import argparse
import json
import math
import os
import subprocess
import sys
import unittest

import numpy as np
import scipy.optimize

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "scripts", "peer"))
import gepeer  # noqa: E402

# Both sides solve the same 5x5 eigenproblem with LAPACK-class QR; the matrices agree to round-off,
# so 1e-9 leaves four orders of magnitude for the conditioning of the eigenvalues.
kEigenvalueTolerance = 1e-9

# The paper's open-loop speed (1.3 x stall) and its landing speed.
kSpeedsMps = (32.0208, 52.21)

# Heights between the table rows, including the paper's boundary H* = 2.7008 m, and heights in the
# first (0.7882-1.0374 m) and last (10.779-13.373 m) intervals, where PCHIP depends on the end-slope
# rule: both the engine and SciPy's PchipInterpolator use MATLAB's three-point shape-preserving end
# slope (docs/model.md).
kBetweenHeightsM = (1.1, 1.45, 1.8, 2.3, 2.7008, 2.8, 4.1, 6.9, 9.5)
kEndIntervalHeightsM = (0.9, 12.0, 13.0)


def match_eigenvalues(a, b):
    """Pairs the eigenvalues of a and b (a permutation of b minimising the total distance)."""
    cost = np.abs(np.subtract.outer(a, b))
    rows, cols = scipy.optimize.linear_sum_assignment(cost)
    return a[rows], b[cols]


class PeerModesTest(unittest.TestCase):
    gesweep = None
    aircraft = None

    def engine_rows(self, args):
        out = subprocess.run([self.gesweep, "modes", "--aircraft", self.aircraft, *args, "--format", "json"],
                             capture_output=True, text=True, cwd=REPO)
        self.assertEqual(out.returncode, 0, f"gesweep modes {' '.join(args)} failed: {out.stderr}")
        return json.loads(out.stdout)["rows"]

    def compare(self, speed_mps, heights_arg, h_derivatives, interpolation):
        args = ["--speed-mps", repr(speed_mps), "--interpolation", interpolation]
        if not h_derivatives:
            args.append("--no-h-derivatives")
        args += ["--table-heights"] if heights_arg is None else ["--heights-m", heights_arg]
        engine = self.engine_rows(args)

        model = gepeer.Model(gepeer.load_aircraft(os.path.join(REPO, self.aircraft)),
                             interpolation=interpolation, h_derivatives=h_derivatives)
        heights = (list(model.heights_m) + [math.inf] if heights_arg is None
                   else [float(v) for v in heights_arg.split(",")])
        self.assertEqual(len(engine), len(heights))
        worst = 0.0
        for row, height_m in zip(engine, heights):
            where = f"u0 {speed_mps} m/s, H {height_m} m, {interpolation}, h-derivatives {h_derivatives}"
            peer = gepeer.analyze_modes(model.state_matrix(height_m, speed_mps))
            lam_engine = np.array([complex(re, im) for re, im in row["eigenvalues"]])
            self.assertEqual(lam_engine.size, 5, where)
            lam_engine, lam_peer = match_eigenvalues(lam_engine, peer["eigenvalues"])
            error = np.abs(lam_engine - lam_peer) / np.maximum(1.0, np.abs(lam_peer))
            worst = max(worst, float(error.max()))
            self.assertLess(error.max(), kEigenvalueTolerance,
                            f"{where}: engine {lam_engine} peer {lam_peer}")
            self.assertEqual(row["classification"], peer["classification"], where)
            for mode in ("short_period", "phugoid", "height"):
                e, p = row["modes"][mode], peer["modes"][mode]
                z_e, z_p = complex(e["re"], e["im"]), complex(p["re"], p["im"])
                self.assertLess(abs(z_e - z_p) / max(1.0, abs(z_p)), kEigenvalueTolerance, f"{where}: {mode}")
                self.assertEqual(e["neutral"], p["neutral"], f"{where}: {mode} neutral")
            self.assertLess(abs(row["stability_margin_per_s"] - peer["stability_margin_per_s"]),
                            kEigenvalueTolerance, f"{where}: sigma")
            self.assertEqual(row["stable"], peer["stable"], where)
        return worst

    def test_table_heights(self):
        for speed in kSpeedsMps:
            for h_derivatives in (True, False):
                for interpolation in ("linear", "pchip"):
                    with self.subTest(speed=speed, h_derivatives=h_derivatives, interpolation=interpolation):
                        worst = self.compare(speed, None, h_derivatives, interpolation)
                        print(f"table heights, u0 {speed}, h-derivatives {h_derivatives}, {interpolation}: "
                              f"worst relative eigenvalue difference {worst:.2e}")

    def test_between_rows(self):
        every = ",".join(repr(h) for h in sorted(kBetweenHeightsM + kEndIntervalHeightsM) + [20.0])
        for speed in kSpeedsMps:
            for h_derivatives in (True, False):
                for interpolation, heights in (("linear", every), ("pchip", every)):
                    with self.subTest(speed=speed, h_derivatives=h_derivatives, interpolation=interpolation):
                        worst = self.compare(speed, heights, h_derivatives, interpolation)
                        print(f"between rows, u0 {speed}, h-derivatives {h_derivatives}, {interpolation}: "
                              f"worst relative eigenvalue difference {worst:.2e}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--gesweep", required=True, help="the gesweep binary")
    parser.add_argument("--aircraft", default="studies/aircraft/ance.toml", help="relative to the repo root")
    args, rest = parser.parse_known_args()
    PeerModesTest.gesweep = os.path.abspath(args.gesweep)
    PeerModesTest.aircraft = args.aircraft
    unittest.main(argv=[sys.argv[0], "-v", *rest])
