#!/usr/bin/python3
"""The Python module's two speed targets (issue 18; docs/performance.md, "From Python"), measured in one
process, medians of alternated repetitions:

1. gesweep.modes over the 10^6 (H, u0) pairs of studies/bench/modes_1e6.toml in one call, against the
   compute-only sweep of that study (the runner with a sink that discards the batches, as
   tests/bench/sweep_throughput.cc --mode compute): target within 10 %. Measured twice: returning new
   arrays (250 MB the kernel must map and zero, which the sweep's reused batches never pay), and
   writing into the arrays of an earlier call (out=), which is the engine's work alone.
2. a call of gesweep.boundary at the paper's speed against the engine's search alone (FindBoundary in
   a C++ loop, the model built once): target at most 10 us more.

    PYTHONPATH=build/python /usr/bin/python3 scripts/lib/python_bench.py [--repetitions N] [--threads T]
"""
import argparse
import json
import pathlib
import resource
import statistics
import sys
import time

import numpy as np

import gesweep
from gesweep import _gesweep

ROOT = pathlib.Path(__file__).resolve().parents[2]
STUDY = ROOT / "studies" / "bench" / "modes_1e6.toml"
SPEED = 32.0208
MODES_TARGET = 0.10          # gesweep.modes within 10 % of the compute-only sweep
BOUNDARY_TARGET_S = 10e-6    # gesweep.boundary at most the search + 10 us


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--json")
    args = parser.parse_args()
    ance = gesweep.Aircraft.load(ROOT / "studies" / "aircraft" / "ance.toml")
    # The study's grid: speed slowest, height fastest (np.linspace / np.geomspace as the study's
    # linspace / logspace).
    u = np.linspace(24.7, 60.0, 500)
    h = np.geomspace(0.79, 14.0, 2000)
    H, U = np.meshgrid(h, u)
    H, U = H.ravel(), U.ravel()

    def cpu():
        usage = resource.getrusage(resource.RUSAGE_SELF)
        return usage.ru_utime + usage.ru_stime

    # Wall clock and the process's CPU time (user + system, all threads): on a machine shared with
    # other work the wall clock of a 2-thread run depends on what the others do; the CPU time much less.
    sweep_s, modes_s, sweep_cpu, modes_cpu, into_s = [], [], [], [], []
    out = gesweep.modes(ance, H, U, threads=args.threads)
    for _ in range(args.repetitions):
        c = cpu()
        seconds, runs = _gesweep._bench_sweep_compute_only(str(STUDY), args.threads)
        sweep_cpu.append(cpu() - c)
        assert runs == H.size
        sweep_s.append(seconds)
        c, start = cpu(), time.perf_counter()
        gesweep.modes(ance, H, U, threads=args.threads)
        modes_s.append(time.perf_counter() - start)
        modes_cpu.append(cpu() - c)
        start = time.perf_counter()
        gesweep.modes(ance, H, U, threads=args.threads, out=out)
        into_s.append(time.perf_counter() - start)
    sweep, modes = statistics.median(sweep_s), statistics.median(modes_s)
    ratio = modes / sweep
    into = statistics.median(into_s)
    ratio_into = into / sweep
    ratio_cpu = statistics.median(modes_cpu) / statistics.median(sweep_cpu)

    calls = 20000
    search_s, call_s = [], []
    gesweep.boundary(ance, SPEED)  # builds and keeps the model
    for _ in range(args.repetitions):
        search_s.append(_gesweep._bench_boundary_search(ance._native, SPEED, calls))
        start = time.perf_counter()
        for _ in range(calls):
            gesweep.boundary(ance, SPEED)
        call_s.append((time.perf_counter() - start) / calls)
    search, call = statistics.median(search_s), statistics.median(call_s)
    overhead = call - search

    print(f"# gesweep from Python: medians of {args.repetitions} alternated repetitions, {args.threads} threads; "
          f"load {open('/proc/loadavg').read().split()[0]}")
    print(f"modes, 10^6 pairs in one call   {modes:8.3f} s ({H.size / modes:,.0f} /s)   compute-only sweep "
          f"{sweep:8.3f} s ({H.size / sweep:,.0f} /s)   ratio {ratio:.3f}   target <= {1 + MODES_TARGET:.2f}: "
          f"{'met' if ratio <= 1 + MODES_TARGET else 'MISSED'}")
    print(f"  into out= (no new arrays)     {into:8.3f} s ({H.size / into:,.0f} /s)   ratio {ratio_into:.3f}   "
          f"target <= {1 + MODES_TARGET:.2f}: {'met' if ratio_into <= 1 + MODES_TARGET else 'MISSED'}")
    print(f"  CPU time (all threads)        {statistics.median(modes_cpu):8.3f} s   compute-only sweep "
          f"{statistics.median(sweep_cpu):8.3f} s   ratio {ratio_cpu:.3f}   target <= {1 + MODES_TARGET:.2f}: "
          f"{'met' if ratio_cpu <= 1 + MODES_TARGET else 'MISSED'}")
    print(f"boundary, one call              {call * 1e6:8.2f} us   engine search alone {search * 1e6:8.2f} us   "
          f"overhead {overhead * 1e6:.2f} us   target <= {BOUNDARY_TARGET_S * 1e6:.0f} us: "
          f"{'met' if overhead <= BOUNDARY_TARGET_S else 'MISSED'}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"modes_s": modes_s, "sweep_compute_only_s": sweep_s, "modes_ratio": ratio,
                       "modes_into_out_s": into_s, "modes_into_out_ratio": ratio_into,
                       "modes_cpu_s": modes_cpu, "sweep_compute_only_cpu_s": sweep_cpu, "modes_ratio_cpu": ratio_cpu,
                       "boundary_call_s": call_s, "boundary_search_s": search_s,
                       "boundary_overhead_s": overhead}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
