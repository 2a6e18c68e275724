#!/usr/bin/python3
"""The engine's frozen linear response to a 1 - cos gust (`gesweep simulate --freeze-derivatives`,
docs/model.md section 9) against SciPy.

The peer builds A from its own model (gepeer.Model.matrices at H0, u0, the Mwdot row folded in) and
the air-relative Eq. (1) by hand: the aerodynamic columns act on the air-relative velocity, so a
vertical gust w_g enters as -A[0:3, w] w_g and, through Mwdot, as -Mwdot dw_g/dt in the pitch row;
the kinematic -dw of the height row stays inertial. The gust is frozen in the air mass: the airplane
meets w_g = (v_m/2)(1 - cos(pi s/d)) at the distance s it has flown through the air since entering it,
ds/dt = u0 + du. That makes the input depend on the response (through du), so it is not an input of
time that scipy.signal.lsim could take; the peer integrates the six states [x, s] with
scipy.integrate.solve_ivp (DOP853) at tight tolerances and compares the height, speed, w, q and theta
series at every 0.05 s sample, and the w_g the engine reports at the same instants.

Usage: peer_gust_test.py --gesweep BUILD/gesweep [--aircraft studies/aircraft/ance.toml]
"""

import argparse
import json
import math
import os
import subprocess
import sys
import unittest

import numpy as np
import scipy.integrate

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "scripts", "peer"))
import gepeer  # noqa: E402

kHeightM = 30.0
kSpeedMps = 32.0208
kAmplitudeMps = 2.0
kHalfLengthM = 30.0
kStartS = 1.0
kDurationS = 12.0
kOutputDtS = 0.05
# Both sides converged (engine dopri5 at 1e-11/1e-13, peer DOP853 at 1e-12/1e-14): they differ by
# their integration errors (well below 1e-8 on states of order 1) and by the engine's series being
# its dense output between steps (4th order, at 1e-11 also below 1e-8). 1e-6 leaves margin and is
# five orders below the gust's effect on the states (~0.1).
kStateTolerance = 1e-6


class PeerGustTest(unittest.TestCase):
    gesweep = None
    aircraft = None

    def engine_series(self):
        command = [self.gesweep, "simulate", "--aircraft", self.aircraft, "--height-m", repr(kHeightM),
                   "--speed-mps", repr(kSpeedMps), "--input", "none", "--freeze-derivatives",
                   "--duration-s", repr(kDurationS), "--output-dt-s", repr(kOutputDtS),
                   "--integrator", "dopri5", "--relative-tolerance", "1e-11", "--absolute-tolerance", "1e-13",
                   "--gust-axis", "w", "--gust-amplitude-mps", repr(kAmplitudeMps),
                   "--gust-half-length-m", repr(kHalfLengthM), "--gust-start-s", repr(kStartS),
                   "--format", "json"]
        out = subprocess.run(command, capture_output=True, text=True, cwd=REPO)
        self.assertEqual(out.returncode, 0, f"{' '.join(command)} failed: {out.stderr}")
        return json.loads(out.stdout)["series"]

    def peer_series(self, times):
        model = gepeer.Model(gepeer.load_aircraft(os.path.join(REPO, self.aircraft)))
        a, _ = model.matrices(kHeightM, kSpeedMps)
        d = model.derivatives(kHeightM, kSpeedMps)
        aero_w = a[:, 1].copy()
        aero_w[4] = 0.0  # the height row's -dw is kinematic
        k = math.pi / kHalfLengthM

        def gust(s):
            if s <= 0.0 or s >= 2.0 * kHalfLengthM:
                return 0.0, 0.0
            return 0.5 * kAmplitudeMps * (1.0 - math.cos(k * s)), 0.5 * kAmplitudeMps * k * math.sin(k * s)

        def rhs(t, y):
            x, s = y[:5], y[5]
            airspeed = kSpeedMps + x[0]  # no u_g: the gust is vertical
            s_dot = airspeed if t >= kStartS else 0.0
            w_g, slope = gust(s)
            w_g_dot = slope * s_dot
            dx = a @ x - aero_w * w_g
            dx[2] -= d["Mwdot"] * w_g_dot
            return np.append(dx, s_dot)

        states = []
        y = np.zeros(6)
        t = 0.0
        # Stop at the gust's entry (the input's jump in ds/dt), as the engine's breakpoint does.
        for end, t_eval in ((kStartS, times[times <= kStartS]), (kDurationS, times[times > kStartS])):
            sol = scipy.integrate.solve_ivp(rhs, (t, end), y, method="DOP853", rtol=1e-12, atol=1e-14,
                                            t_eval=t_eval, dense_output=False)
            self.assertTrue(sol.success, sol.message)
            states.append(sol.y)
            y = scipy.integrate.solve_ivp(rhs, (t, end), y, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
            t = end
        y_all = np.concatenate(states, axis=1)
        w_g = np.array([gust(s)[0] for s in y_all[5]])
        return y_all[:5], w_g

    def test_frozen_response_to_a_vertical_gust(self):
        engine = self.engine_series()
        times = np.array(engine["time_s"], dtype=float)
        peer, w_g = self.peer_series(times)
        columns = {"delta_u_mps": 0, "delta_w_mps": 1, "pitch_rate_radps": 2, "delta_theta_rad": 3,
                   "delta_h_m": 4}
        largest = 0.0
        for name, row in columns.items():
            values = np.array(engine[name], dtype=float)
            difference = np.abs(values - peer[row])
            largest = max(largest, difference.max())
            self.assertLess(difference.max(), kStateTolerance, name)
        self.assertLess(np.abs(np.array(engine["w_g_mps"], dtype=float) - w_g).max(), kStateTolerance, "w_g")
        # The gust moves the airplane (the test can fail): w reaches a good part of the amplitude.
        self.assertGreater(np.abs(peer[1]).max(), 0.2 * kAmplitudeMps)
        print(f"frozen 1 - cos gust: largest state difference {largest:.2e} over {len(times)} samples")


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--gesweep", required=True, help="the gesweep binary")
    parser.add_argument("--aircraft", default="studies/aircraft/ance.toml", help="relative to the repo root")
    args, rest = parser.parse_known_args()
    PeerGustTest.gesweep = os.path.abspath(args.gesweep)
    PeerGustTest.aircraft = args.aircraft
    unittest.main(argv=[sys.argv[0], "-v", *rest])
