#!/usr/bin/python3
"""gepeer: the NumPy/SciPy script a user would otherwise write for the gesweep model.

An independent implementation of docs/model.md (the engine's C++ was not consulted):
the aircraft file (TOML), table interpolation (§2), CDh from the drag polar (§3), the dimensional
derivatives of the paper's Table 1 (§4), A and B of Eq. (1) (§5), the modes and the stability
margin σ (§6), the open-loop response with derivatives re-evaluated at every right-hand-side call
(§7) by a plain NumPy RK4 and by scipy.integrate.solve_ivp, and the LQR by
scipy.linalg.solve_continuous_are.

It serves two purposes: an oracle for the engine that shares no code with it (tests/peer), and the
baseline the engine's speed is measured against (scripts/peer/bench_peer.py). It is written the way
a competent user would write it: plain, vectorised where natural, not tuned.

Run `/usr/bin/python3 scripts/peer/gepeer.py --help` (Debian's python3 has numpy and scipy).
"""

import argparse
import json
import math
import sys
import tomllib

import numpy as np
import scipy.integrate
import scipy.interpolate
import scipy.linalg
import scipy.optimize

GRAVITY_MPS2 = 9.80665

# ISA troposphere (ISO 2533): sea-level temperature, lapse rate, specific gas constant of dry air.
# docs/model.md §1 fixes g and rho0 = 1.225 kg/m^3; the rest are the standard's values.
ISA_SEA_LEVEL_DENSITY_KGPM3 = 1.225
ISA_SEA_LEVEL_TEMPERATURE_K = 288.15
ISA_LAPSE_RATE_KPM = 0.0065
ISA_GAS_CONSTANT_JPKGK = 287.05287

# docs/model.md §6: a real eigenvalue this small is the neutral free-flight height mode.
NEUTRAL_EIGENVALUE_PER_S = 1e-9

# The columns of the aircraft table that the model uses, in a fixed order; CDh is derived (§3).
TABLE_COLUMNS = ("k", "CLo", "CMo", "CDalpha", "CLalpha", "CLalphadot", "CLq", "CLde", "CMalpha",
                 "CMalphadot", "CMq", "CMde", "CLh", "CMh")
COLUMNS = TABLE_COLUMNS + ("CDh",)
COL = {name: i for i, name in enumerate(COLUMNS)}

STATE_NAMES = ("du_mps", "dw_mps", "q_radps", "dtheta_rad", "dH_m")


# ----------------------------------------------------------------------------------------------
# Aircraft file and the interpolated coefficient table (docs/model.md §2, §3)
# ----------------------------------------------------------------------------------------------

def load_aircraft(path):
    """Reads an aircraft TOML file into a plain dict of SI numbers and NumPy arrays."""
    with open(path, "rb") as f:
        doc = tomllib.load(f)
    table = doc["table"]
    free = table["free_flight"]
    heights = np.array(table["height_m"], dtype=float)
    rows = np.column_stack([np.array(table[name], dtype=float) for name in TABLE_COLUMNS])
    free_row = np.array([float(free[name]) for name in TABLE_COLUMNS])
    if rows.shape[0] != heights.size or np.any(np.diff(heights) <= 0):
        raise ValueError(f"{path}: [table] columns must match height_m, which must increase")
    return {
        "name": doc.get("name", path),
        "wingspan_m": float(doc["geometry"]["wingspan_m"]),
        "chord_m": float(doc["geometry"]["mean_chord_m"]),
        "area_m2": float(doc["geometry"]["wing_area_m2"]),
        "mass_kg": float(doc["mass"]["mass_kg"]),
        "iy_kgm2": float(doc["mass"]["pitch_inertia_kgm2"]),
        "CDo": float(doc["aerodynamics"]["CDo"]),
        "CDu": float(doc["aerodynamics"].get("CDu", 0.0)),
        "CLu": float(doc["aerodynamics"].get("CLu", 0.0)),
        "CMu": float(doc["aerodynamics"].get("CMu", 0.0)),
        "CDde": float(doc["aerodynamics"].get("CDde", 0.0)),
        "stall_speed_mps": float(doc["limits"]["stall_speed_mps"]),
        "contact_height_m": float(doc["limits"]["wheel_contact_height_m"]),
        "field_elevation_m": float(doc["limits"].get("field_elevation_m", 0.0)),
        "heights_m": heights,
        "rows": rows,
        "free_row": free_row,
    }


def isa_density(altitude_m):
    """ISA troposphere density, kg/m^3, at an altitude above sea level taken as geopotential (docs/model.md §1)."""
    exponent = GRAVITY_MPS2 / (ISA_GAS_CONSTANT_JPKGK * ISA_LAPSE_RATE_KPM) - 1.0
    ratio = 1.0 - ISA_LAPSE_RATE_KPM * altitude_m / ISA_SEA_LEVEL_TEMPERATURE_K
    return ISA_SEA_LEVEL_DENSITY_KGPM3 * ratio ** exponent


class Model:
    """The interpolated model of one aircraft with the options of docs/model.md (§2-§5)."""

    def __init__(self, aircraft, interpolation="linear", h_derivatives=True, cdh="polar"):
        if interpolation not in ("linear", "pchip"):
            raise ValueError(f"interpolation {interpolation!r}: expected linear or pchip")
        if cdh not in ("polar", "zero"):
            raise ValueError(f"cdh {cdh!r}: expected polar or zero")
        self.ac = aircraft
        self.interpolation = interpolation
        self.h_derivatives = h_derivatives
        self.cdh = cdh
        heights = aircraft["heights_m"]
        rows = aircraft["rows"]
        # §3: CDh = d(k CLo^2)/dh on the finite rows, h = H/c; zero in free flight.
        if cdh == "polar":
            polar = rows[:, COL["k"]] * rows[:, COL["CLo"]] ** 2
            cdh_rows = np.gradient(polar, heights / aircraft["chord_m"], edge_order=1)
        else:
            cdh_rows = np.zeros_like(heights)
        self.heights_m = heights
        self.rows = np.column_stack([rows, cdh_rows])
        self.free_row = np.append(aircraft["free_row"], 0.0)
        self._pchip = (scipy.interpolate.PchipInterpolator(heights, self.rows, axis=0)
                       if interpolation == "pchip" else None)

    def coefficients(self, height_m):
        """All columns (order COLUMNS) at height H: held below the first row, free flight above the last."""
        heights = self.heights_m
        if math.isnan(height_m):  # a diverging run; let the NaN propagate to the diverged check
            return np.full(len(COLUMNS), np.nan)
        if height_m > heights[-1]:
            return self.free_row
        if height_m <= heights[0]:
            return self.rows[0]
        if self._pchip is not None:
            return self._pchip(height_m)
        i = np.searchsorted(heights, height_m) - 1
        w = (height_m - heights[i]) / (heights[i + 1] - heights[i])
        return (1.0 - w) * self.rows[i] + w * self.rows[i + 1]

    def density(self, height_m):
        """rho(H); in free flight (H = inf) the density at field elevation."""
        if math.isinf(height_m):
            return isa_density(self.ac["field_elevation_m"])
        return isa_density(self.ac["field_elevation_m"] + height_m)

    def derivatives(self, height_m, speed_mps):
        """The dimensional derivatives of the paper's Table 1 (docs/model.md §4) at H and u, as a dict."""
        ac = self.ac
        c = self.coefficients(height_m)
        u = speed_mps
        chord, area, mass, iy = ac["chord_m"], ac["area_m2"], ac["mass_kg"], ac["iy_kgm2"]
        qs = 0.5 * self.density(height_m) * u * u * area
        d = {
            "Xu": -(ac["CDu"] + 2 * ac["CDo"]) * qs / (mass * u),
            "Xw": -(c[COL["CDalpha"]] - c[COL["CLo"]]) * qs / (mass * u),
            "Xh": -c[COL["CDh"]] * qs / (mass * chord),
            "Xde": -ac["CDde"] * qs / mass,
            "Zu": -(ac["CLu"] + 2 * c[COL["CLo"]]) * qs / (mass * u),
            "Zw": -(c[COL["CLalpha"]] + ac["CDo"]) * qs / (mass * u),
            "Zh": -c[COL["CLh"]] * qs / (mass * chord),
            "Zde": -c[COL["CLde"]] * qs / mass,
            "Mu": ac["CMu"] * qs * chord / (iy * u),
            "Mw": c[COL["CMalpha"]] * qs * chord / (iy * u),
            "Mwdot": c[COL["CMalphadot"]] * (chord / (2 * u)) * qs * chord / (iy * u),
            "Mq": c[COL["CMq"]] * (chord / (2 * u)) * qs * chord / iy,
            "Mh": c[COL["CMh"]] * qs / iy,
            "Mde": c[COL["CMde"]] * qs * chord / iy,
        }
        if not self.h_derivatives:
            d["Xh"] = d["Zh"] = d["Mh"] = 0.0
        return d

    def matrices(self, height_m, speed_mps, reference_speed_mps=None):
        """A and B of Eq. (1) (docs/model.md §5) with the derivatives at H and u.

        The kinematic u0 entries (row dw, column q; row dH, column dtheta) use reference_speed_mps
        (default: speed_mps), as in the open-loop response of §7. The pitch row is the moment
        equation with dw/dt substituted from the dw row, so Mwdot multiplies that row.
        """
        u0 = speed_mps if reference_speed_mps is None else reference_speed_mps
        d = self.derivatives(height_m, speed_mps)
        g = GRAVITY_MPS2
        a = np.array([
            [d["Xu"], d["Xw"], 0.0, -g, d["Xh"]],
            [d["Zu"], d["Zw"], u0, 0.0, d["Zh"]],
            [d["Mu"], d["Mw"], d["Mq"], 0.0, d["Mh"]],
            [0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0, u0, 0.0],
        ])
        b = np.array([d["Xde"], d["Zde"], d["Mde"], 0.0, 0.0])
        a[2] += d["Mwdot"] * a[1]
        b[2] += d["Mwdot"] * b[1]
        return a, b

    def state_matrix(self, height_m, speed_mps):
        return self.matrices(height_m, speed_mps)[0]


# ----------------------------------------------------------------------------------------------
# Modes and stability margin (docs/model.md §6)
# ----------------------------------------------------------------------------------------------

def mode_properties(lam):
    lam = complex(lam)
    magnitude = abs(lam)
    neutral = lam.imag == 0.0 and magnitude <= NEUTRAL_EIGENVALUE_PER_S
    return {
        "re": lam.real,
        "im": lam.imag,
        "natural_frequency_radps": magnitude,
        "damping_ratio": -lam.real / magnitude if magnitude > 0 else None,
        "period_s": 2 * math.pi / abs(lam.imag) if lam.imag != 0 else None,
        "time_to_half_or_double_s": math.log(2) / abs(lam.real) if lam.real != 0 else None,
        "oscillatory": lam.imag != 0.0,
        "neutral": bool(neutral),
    }


def analyze_modes(a):
    """Eigenvalues of A, the short-period / phugoid / height modes and sigma (docs/model.md §6)."""
    lam = np.linalg.eigvals(a)
    pairs = lam[lam.imag > 0]                       # one member (Im > 0) of each complex pair
    reals = np.sort_complex(lam[lam.imag == 0])
    reals = reals[np.argsort(np.abs(reals))]        # by magnitude, smallest first
    pairs = pairs[np.argsort(-np.abs(pairs.imag))]  # largest |Im| first
    if pairs.size == 2:
        classification = "standard"
        short_period, phugoid, height = pairs[0], pairs[1], reals[0]
    elif pairs.size == 1:
        # A pair split into two real roots: the two larger real roots are that pair. It is the
        # short period if they are larger in magnitude than the remaining complex pair.
        split = reals[1:]
        dominant = split[np.argmax(split.real)]
        if np.max(np.abs(split)) > abs(pairs[0]):
            classification = "short_period_real"
            short_period, phugoid = dominant, pairs[0]
        else:
            classification = "phugoid_real"
            short_period, phugoid = pairs[0], dominant
        height = reals[0]
    else:
        classification = "all_real"
        height = reals[0]
        phugoid = reals[1:3][np.argmax(reals[1:3].real)]
        short_period = reals[3:5][np.argmax(reals[3:5].real)]
    non_neutral = [z for z in lam if not (z.imag == 0 and abs(z) <= NEUTRAL_EIGENVALUE_PER_S)]
    sigma = max(z.real for z in non_neutral)
    return {
        "eigenvalues": lam,
        "modes": {"short_period": mode_properties(short_period), "phugoid": mode_properties(phugoid),
                  "height": mode_properties(height)},
        "classification": classification,
        "stability_margin_per_s": sigma,
        "stable": bool(sigma < 0),
    }


# ----------------------------------------------------------------------------------------------
# Open-loop response (docs/model.md §7)
# ----------------------------------------------------------------------------------------------

class OpenLoop:
    """The open-loop problem: dx/dt = A(H, u) x + B(H, u) de(t), derivatives re-evaluated per call."""

    def __init__(self, model, height_m, speed_mps, elevator_deg=5.0, pulse_s=0.2):
        self.model = model
        self.h0 = height_m
        self.u0 = speed_mps
        self.elevator_rad = math.radians(elevator_deg)
        self.pulse_s = pulse_s
        self.contact_m = model.ac["contact_height_m"]
        self.stall_mps = model.ac["stall_speed_mps"]
        self.rhs_calls = 0

    def elevator(self, t):
        return self.elevator_rad if 0.0 <= t < self.pulse_s else 0.0

    def rhs(self, t, x):
        """The right-hand side with the elevator sampled at t (the input's own discontinuities included)."""
        return self.rhs_with_elevator(t, x, self.elevator(t))

    def rhs_with_elevator(self, t, x, elevator_rad):
        """The right-hand side with a given elevator angle, for integrating between breakpoints."""
        self.rhs_calls += 1
        a, b = self.model.matrices(self.h0 + x[4], self.u0 + x[0], reference_speed_mps=self.u0)
        return a @ x + b * elevator_rad

    def elevator_between(self, t0, t1):
        """The (constant) elevator angle on an interval (t0, t1) that contains no breakpoint."""
        return self.elevator(0.5 * (t0 + t1))

    def breakpoints(self, duration_s):
        """Times in (0, duration_s) where the input jumps: the end of the pulse."""
        return [t for t in (self.pulse_s,) if 0.0 < t < duration_s]

    # Event functions: negative once the run has to end.
    def touchdown(self, t, x):
        return self.h0 + x[4] - self.contact_m

    def stall(self, t, x):
        return self.u0 + x[0] - self.stall_mps


def _summary(end_event, end_time_s, times, states, h0, steps, rhs_calls):
    heights = h0 + states[:, 4]
    i_min = int(np.argmin(heights))
    return {
        "end_event": end_event,
        "end_time_s": float(end_time_s),
        "min_height_m": float(heights[i_min]),
        "min_height_time_s": float(times[i_min]),
        "max_abs_q_radps": float(np.max(np.abs(states[:, 2]))),
        "final_state": [float(v) for v in states[-1]],
        "steps": int(steps),
        "rhs_calls": int(rhs_calls),
    }


def rk4_step(f, t, x, dt, *args):
    k1 = f(t, x, *args)
    k2 = f(t + dt / 2, x + dt / 2 * k1, *args)
    k3 = f(t + dt / 2, x + dt / 2 * k2, *args)
    k4 = f(t + dt, x + dt * k3, *args)
    return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def simulate_rk4(problem, dt_s=0.015, duration_s=30.0, breakpoints=False):
    """Classical fixed-step RK4 (the paper's), with touchdown / stall / time-limit / diverged ends.

    Time is n*dt (no accumulated round-off); the last step is shortened to end at duration_s.
    breakpoints=False is the paper's plain RK4: every stage samples the pulse at its own time, so
    the step that straddles the end of the pulse sees part of it. breakpoints=True splits such a
    step at the jump and holds the elevator constant on each part.
    An event inside a step is located by a root finder on the length of a partial RK4 step from
    the start of that step, and the run ends there.
    """
    problem.rhs_calls = 0
    jumps = problem.breakpoints(duration_s) if breakpoints else []

    def advance(t, x, dt):
        if not breakpoints:
            return rk4_step(problem.rhs, t, x, dt)
        cuts = [t] + [tb for tb in jumps if t < tb < t + dt] + [t + dt]
        for t0, t1 in zip(cuts[:-1], cuts[1:]):
            x = rk4_step(problem.rhs_with_elevator, t0, x, t1 - t0, problem.elevator_between(t0, t1))
        return x

    n_steps = int(math.ceil(duration_s / dt_s - 1e-9))
    x = np.zeros(5)
    times = [0.0]
    states = [x]
    events = (("touchdown", problem.touchdown), ("stall", problem.stall))
    for n in range(n_steps):
        t = n * dt_s
        t_next = min((n + 1) * dt_s, duration_s)
        x_new = advance(t, x, t_next - t)
        if not np.all(np.isfinite(x_new)):
            return _summary("diverged", t_next, np.array(times), np.array(states), problem.h0, n + 1,
                            problem.rhs_calls) | {"final_state": [float(v) for v in x_new]}
        for name, event in events:
            if event(t_next, x_new) <= 0.0:
                def g(tau):
                    return event(t + tau, advance(t, x, tau))
                tau = scipy.optimize.brentq(g, 0.0, t_next - t, xtol=1e-13, rtol=1e-15)
                times.append(t + tau)
                states.append(advance(t, x, tau))
                return _summary(name, t + tau, np.array(times), np.array(states), problem.h0, n + 1,
                                problem.rhs_calls)
        x = x_new
        times.append(t_next)
        states.append(x)
    return _summary("time_limit", duration_s, np.array(times), np.array(states), problem.h0, n_steps,
                    problem.rhs_calls)


def simulate_solve_ivp(problem, duration_s=30.0, rtol=1e-6, atol=1e-9, method="RK45", breakpoints=True):
    """The same run by scipy.integrate.solve_ivp with terminal events.

    With breakpoints=True (default) the run is integrated piecewise between the input's jumps with
    the elevator held constant on each piece, so no step straddles a discontinuity; False
    integrates 0..duration_s in one call with the elevator sampled at each stage time.
    """
    problem.rhs_calls = 0

    def touchdown(t, x, *args):
        return problem.touchdown(t, x)

    def stall(t, x, *args):
        return problem.stall(t, x)

    for event in (touchdown, stall):
        event.terminal = True
        event.direction = -1
    if breakpoints:
        cuts = [0.0] + problem.breakpoints(duration_s) + [duration_s]
        pieces = [(problem.rhs_with_elevator, (t0, t1), (problem.elevator_between(t0, t1),))
                  for t0, t1 in zip(cuts[:-1], cuts[1:])]
    else:
        pieces = [(problem.rhs, (0.0, duration_s), None)]
    x = np.zeros(5)
    times, states = [np.array([0.0])], [x[None, :]]
    steps = 0
    for fun, span, args in pieces:
        sol = scipy.integrate.solve_ivp(fun, span, x, method=method, rtol=rtol, atol=atol,
                                        events=(touchdown, stall), args=args)
        steps += sol.t.size - 1
        times.append(sol.t[1:])
        states.append(sol.y.T[1:])
        if sol.status == -1 or not np.all(np.isfinite(sol.y)):
            return _summary("diverged", sol.t[-1], np.concatenate(times), np.concatenate(states),
                            problem.h0, steps, problem.rhs_calls)
        if sol.status == 1:
            name = "touchdown" if sol.t_events[0].size else "stall"
            t_end = (sol.t_events[0] if sol.t_events[0].size else sol.t_events[1])[0]
            return _summary(name, t_end, np.concatenate(times), np.concatenate(states),
                            problem.h0, steps, problem.rhs_calls)
        x = sol.y[:, -1]
    return _summary("time_limit", duration_s, np.concatenate(times), np.concatenate(states),
                    problem.h0, steps, problem.rhs_calls)


# ----------------------------------------------------------------------------------------------
# LQR (docs/model.md §8; issue 4's Lqr and Lqry)
# ----------------------------------------------------------------------------------------------

def lqr(a, b, q, r, n=None):
    """K, S and the closed-loop eigenvalues for u = -K x minimising the integral of
    x'Qx + u'Ru + 2x'Nu, by scipy.linalg.solve_continuous_are."""
    a, b, q, r = (np.atleast_2d(np.asarray(m, dtype=float)) for m in (a, b, q, r))
    if b.shape[0] != a.shape[0]:
        b = b.T
    n = np.zeros(b.shape) if n is None else np.atleast_2d(np.asarray(n, dtype=float)).reshape(b.shape)
    s = scipy.linalg.solve_continuous_are(a, b, q, r, s=n)
    k = np.linalg.solve(r, b.T @ s + n.T)
    return {"K": k, "S": s, "closed_loop_eigenvalues": np.linalg.eigvals(a - b @ k)}


def lqry(a, b, c, d, q, r):
    """MATLAB's lqry: output weighting, Qbar = C'QC, Rbar = R + D'QD, Nbar = C'QD."""
    a, b, c, d, q, r = (np.atleast_2d(np.asarray(m, dtype=float)) for m in (a, b, c, d, q, r))
    return lqr(a, b, c.T @ q @ c, r + d.T @ q @ d, c.T @ q @ d)


# ----------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------

def _json_number(v):
    if v is None:
        return None
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return v


def _add_model_flags(p):
    p.add_argument("--aircraft", required=True, help="aircraft TOML, e.g. studies/aircraft/ance.toml")
    p.add_argument("--interpolation", default="linear", choices=("linear", "pchip"))
    p.add_argument("--cdh", default="polar", choices=("polar", "zero"))
    p.add_argument("--no-h-derivatives", action="store_true", help="leave out Xh, Zh, Mh")
    p.add_argument("--speed-mps", type=float, required=True, help="reference speed u0, m/s")


def _model(args):
    return Model(load_aircraft(args.aircraft), interpolation=args.interpolation,
                 h_derivatives=not args.no_h_derivatives, cdh=args.cdh)


def modes_rows(model, heights_m, speed_mps):
    rows = []
    for h in heights_m:
        m = analyze_modes(model.state_matrix(h, speed_mps))
        rows.append({
            "height_m": _json_number(h),
            "height_over_span": _json_number(h / model.ac["wingspan_m"]),
            "eigenvalues": [[z.real, z.imag] for z in m["eigenvalues"]],
            "modes": {k: {kk: _json_number(vv) for kk, vv in v.items()} for k, v in m["modes"].items()},
            "classification": m["classification"],
            "stability_margin_per_s": m["stability_margin_per_s"],
            "stable": m["stable"],
        })
    return rows


def _cmd_modes(args):
    model = _model(args)
    if args.table_heights:
        heights = list(model.heights_m) + [math.inf]
    else:
        heights = [float(v) for v in args.heights_m.split(",")]
    rows = modes_rows(model, heights, args.speed_mps)
    if args.format == "json":
        print(json.dumps({"speed_mps": args.speed_mps, "rows": rows}, indent=2))
    else:
        print(f"{'H_m':>9} {'short period':>24} {'phugoid':>24} {'height':>12} {'sigma_per_s':>12} stable")
        for r in rows:
            sp, ph, hm = (r["modes"][k] for k in ("short_period", "phugoid", "height"))
            print(f"{r['height_m']:>9} {sp['re']:>11.5f}{sp['im']:+.5f}i {ph['re']:>11.5f}{ph['im']:+.5f}i "
                  f"{hm['re']:>12.5f} {r['stability_margin_per_s']:>12.3e} {'yes' if r['stable'] else 'NO'}")


def _cmd_simulate(args):
    problem = OpenLoop(_model(args), args.height_m, args.speed_mps, args.elevator_deg, args.pulse_s)
    if args.integrator == "rk4":
        summary = simulate_rk4(problem, args.dt_s, args.duration_s, breakpoints=not args.no_breakpoints)
    else:
        summary = simulate_solve_ivp(problem, args.duration_s, args.rtol, args.atol,
                                     breakpoints=not args.no_breakpoints)
    print(json.dumps({"summary": summary}, indent=2))


def _cmd_lqr(args):
    with open(args.matrices) as f:
        m = json.load(f)
    if "C" in m:
        result = lqry(m["A"], m["B"], m["C"], m.get("D", np.zeros((len(m["C"]), np.atleast_2d(m["B"]).shape[1]))),
                      m["Q"], m["R"])
    else:
        result = lqr(m["A"], m["B"], m["Q"], m["R"], m.get("N"))
    print(json.dumps({"K": result["K"].tolist(), "S": result["S"].tolist(),
                      "closed_loop_eigenvalues": [[z.real, z.imag] for z in result["closed_loop_eigenvalues"]]},
                     indent=2))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("modes", help="eigenvalues, modes and sigma of Eq. (1) (docs/model.md §6)")
    _add_model_flags(p)
    group = p.add_mutually_exclusive_group(required=True)
    group.add_argument("--heights-m", help="comma-separated heights, m (inf: free flight)")
    group.add_argument("--table-heights", action="store_true", help="the table heights and free flight")
    p.add_argument("--format", default="table", choices=("table", "json"))
    p.set_defaults(func=_cmd_modes)

    p = sub.add_parser("simulate", help="open-loop response to an elevator pulse (docs/model.md §7)")
    _add_model_flags(p)
    p.add_argument("--height-m", type=float, required=True, help="starting height H0, m")
    p.add_argument("--elevator-deg", type=float, default=5.0)
    p.add_argument("--pulse-s", type=float, default=0.2)
    p.add_argument("--integrator", default="rk4", choices=("rk4", "solve_ivp"))
    p.add_argument("--dt-s", type=float, default=0.015, help="RK4 step, s")
    p.add_argument("--duration-s", type=float, default=30.0)
    p.add_argument("--rtol", type=float, default=1e-6, help="solve_ivp relative tolerance")
    p.add_argument("--atol", type=float, default=1e-9, help="solve_ivp absolute tolerance")
    p.add_argument("--no-breakpoints", action="store_true",
                   help="let steps straddle the end of the pulse (the paper's plain RK4)")
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser("lqr", help="LQR by scipy.linalg.solve_continuous_are of matrices in a JSON file")
    p.add_argument("--matrices", required=True,
                   help='JSON {"A","B","Q","R"[,"N"]} or, for lqry, {"A","B","C"[,"D"],"Q","R"}')
    p.set_defaults(func=_cmd_lqr)

    args = parser.parse_args(argv)
    args.func(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
