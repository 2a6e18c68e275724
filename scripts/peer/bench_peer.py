#!/usr/bin/python3
"""Times the NumPy/SciPy peer (gepeer.py) per analysis and prints JSON.

The same work as the engine's benchmarks (issue 9), so `./scripts/bench --peer` can print the two
side by side with ratios:
  modes            one eigen-analysis with mode identification at one height, A built from the table
  eigen_analysis   the same on a fixed A (numpy.linalg.eigvals + identification only)
  rhs              one right-hand-side evaluation of the open loop (derivatives re-evaluated)
  open_loop_rk4    one 30 s open-loop run, plain RK4 at 0.015 s (2000 steps, 8000 RHS calls)
  open_loop_solve_ivp_rtol1e-3 / _rtol1e-6   the same run by solve_ivp (RK45), pulse end as breakpoint
  lqr              one scipy.linalg.solve_continuous_are + gain (5-state Eq. (1), Q = I, R = 1,
                   or the matrices of --lqr-matrices)

Each figure is the median over --repeats repetitions; a repetition of a fast operation times a
batch of calls and divides. Run with Debian's python: /usr/bin/python3 scripts/peer/bench_peer.py
"""

import argparse
import json
import os
import platform
import statistics
import sys
import time

import numpy as np
import scipy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gepeer  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def measure(function, repeats, min_batch_s=0.2):
    """Seconds per call of function(), over `repeats` batches: wall-clock median, min and max, and
    the median of process CPU time (which a machine shared with other work inflates less)."""
    start = time.perf_counter()
    function()
    single = time.perf_counter() - start
    batch = max(1, int(min_batch_s / max(single, 1e-9)))
    wall, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        for _ in range(batch):
            function()
        wall.append((time.perf_counter() - start) / batch)
        cpu.append((time.process_time() - start_cpu) / batch)
    median = statistics.median(wall)
    return {"median_s": median, "min_s": min(wall), "max_s": max(wall), "cpu_median_s": statistics.median(cpu),
            "per_s": 1.0 / median, "repeats": repeats, "calls_per_repeat": batch}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--aircraft", default=os.path.join(REPO, "studies/aircraft/ance.toml"))
    parser.add_argument("--repeats", type=int, default=7, help="repetitions per figure (median taken)")
    parser.add_argument("--height-m", type=float, default=2.0748, help="height of the modes and open-loop runs")
    parser.add_argument("--open-loop-height-m", type=float, default=5.5922,
                        help="start height of the open-loop runs (5.5922 m stays airborne for 30 s)")
    parser.add_argument("--speed-mps", type=float, default=32.0208)
    parser.add_argument("--lqr-matrices", help='JSON {"A","B","Q","R"} to time instead of the default')
    parser.add_argument("--only", help="comma-separated subset of the figures")
    args = parser.parse_args(argv)

    model = gepeer.Model(gepeer.load_aircraft(args.aircraft))
    u0 = args.speed_mps
    a_fixed = model.state_matrix(args.height_m, u0)

    def open_loop():
        return gepeer.OpenLoop(model, args.open_loop_height_m, u0, 5.0, 0.2)

    def run_rk4():
        summary = gepeer.simulate_rk4(open_loop(), 0.015, 30.0, breakpoints=False)
        assert summary["end_event"] == "time_limit" and summary["steps"] == 2000, summary

    def run_ivp(rtol, atol):
        def run():
            summary = gepeer.simulate_solve_ivp(open_loop(), 30.0, rtol=rtol, atol=atol)
            assert summary["end_event"] == "time_limit", summary
        return run

    rhs_problem = open_loop()
    x_rhs = np.array([0.3, -0.01, 0.02, 0.003, -0.5])

    if args.lqr_matrices:
        with open(args.lqr_matrices) as f:
            m = json.load(f)
        lqr_a, lqr_b, lqr_q, lqr_r = m["A"], m["B"], m["Q"], m["R"]
        lqr_what = f"matrices of {args.lqr_matrices}"
    else:
        lqr_a, lqr_b = model.matrices(args.height_m, u0)
        lqr_b = lqr_b[:, None]
        lqr_q, lqr_r = np.eye(5), np.eye(1)
        lqr_what = f"Eq. (1) at {args.height_m} m, {u0} m/s, Q = I5, R = 1"

    figures = {
        "modes": (lambda: gepeer.analyze_modes(model.state_matrix(args.height_m, u0)),
                  f"A(H, u0) from the table + eigvals + identification, H {args.height_m} m, u0 {u0} m/s"),
        "eigen_analysis": (lambda: gepeer.analyze_modes(a_fixed), "eigvals + identification of a fixed A"),
        "rhs": (lambda: rhs_problem.rhs(0.1, x_rhs), "one open-loop right-hand side, derivatives re-evaluated"),
        "open_loop_rk4": (run_rk4, f"30 s, plain RK4 dt 0.015 s, from {args.open_loop_height_m} m, 5 deg / 0.2 s"),
        "open_loop_solve_ivp_rtol1e-3": (run_ivp(1e-3, 1e-6), "30 s, solve_ivp RK45 rtol 1e-3 atol 1e-6"),
        "open_loop_solve_ivp_rtol1e-6": (run_ivp(1e-6, 1e-9), "30 s, solve_ivp RK45 rtol 1e-6 atol 1e-9"),
        "lqr": (lambda: gepeer.lqr(lqr_a, lqr_b, lqr_q, lqr_r), f"solve_continuous_are + K, {lqr_what}"),
    }
    selected = list(figures) if not args.only else args.only.split(",")
    unknown = [name for name in selected if name not in figures]
    if unknown:
        parser.error(f"--only: unknown figure(s) {unknown}; expected some of {list(figures)}")

    results = {}
    for name in selected:
        function, what = figures[name]
        figure = measure(function, args.repeats) | {"what": what}
        results[name] = figure
        print(f"{name:30s} {figure['median_s'] * 1e6:12.1f} us wall {figure['cpu_median_s'] * 1e6:12.1f} us cpu",
              file=sys.stderr)

    report = {
        "peer": "scripts/peer/gepeer.py",
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "machine": platform.machine(),
        "cpu_count": os.cpu_count(),
        "unit": "seconds per call: wall-clock median over repeats (per_s = 1/median), and CPU-time median",
        "results": results,
    }
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
