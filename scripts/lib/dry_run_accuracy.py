#!/usr/bin/python3
"""How close `gesweep run --dry-run` comes to the real run, on the shipped studies (docs/sweep.md,
"Dry run"; issue 19's target: within 30 % on a quiet machine).

    /usr/bin/python3 scripts/lib/dry_run_accuracy.py GESWEEP [--repetitions N] [--threads T] [--json FILE]
    ./scripts/bench --dry-run                      # the same through the benchmark script

For each study under studies/ (the 10^7-run modes_1e7.toml excepted: its real run takes minutes and
gigabytes) it runs, alternately in one invocation, N dry runs (--format json) and N real runs into a
scratch archive, and prints the median estimate with the median of its 95 % interval, the median
real wall time (gesweep's own "N runs in T" line: from the archive's set-up to its close, the
interval the estimate covers; process start-up and reading the study are in neither), their ratio,
the spread of the estimates (max/min over the repetitions), the median of the estimate's measured
per-sweep part, and the ratio the estimate would have without it and without the first batch's
pass through the pipeline (runs x the steady wall time per run alone, as before issue 19's last
change), from the same dry runs. The load average is printed before and after."""
import argparse
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXCLUDED = {"modes_1e7.toml"}


def seconds(text):
    """gesweep's FormatDuration: "1.2 s", "45 s", "3:05", "1:02:03", "2d 1:02:03"."""
    text = text.strip()
    if text.endswith(" s"):
        return float(text[:-2])
    days = 0
    if "d " in text:
        day_text, text = text.split("d ", 1)
        days = int(day_text)
    parts = [int(p) for p in text.split(":")]
    while len(parts) < 3:
        parts.insert(0, 0)
    return days * 86400 + parts[0] * 3600 + parts[1] * 60 + parts[2]


def real_run(gesweep, study, archive, threads):
    result = subprocess.run([gesweep, "run", str(study), "-o", str(archive), "--force", "--threads", str(threads)],
                            capture_output=True, text=True)
    if result.returncode not in (0, 3):
        raise RuntimeError(f"{study}: exit {result.returncode}: {result.stderr.strip()[-300:]}")
    match = re.search(r"gesweep: (\d+) runs in (.+?) \(", result.stderr)
    return seconds(match.group(2)) if match else float("nan")


def steady_only(report, threads, cores):
    """The estimate without its per-sweep terms: runs x the pipeline's steady wall time per run
    (engine/sweep/run_cost.h, SteadyWallPerRun)."""
    work = report["seconds_per_run"] + (report["encode_seconds_per_run"] or 0)
    store = report["write_seconds_per_run"] or 0
    busy = min(threads + 1, cores)
    return report["run_count"] * max(work / threads, store, (work + store) / busy)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("gesweep")
    parser.add_argument("--repetitions", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--json")
    args = parser.parse_args()
    studies = sorted(p for p in (ROOT / "studies").rglob("*.toml")
                     if "aircraft" not in p.parts and p.name not in EXCLUDED)
    rows = []
    cores = os.cpu_count() or 1
    load_before = os.getloadavg()
    print(f"# load average before: {load_before[0]:.2f} {load_before[1]:.2f} {load_before[2]:.2f}")
    print(f"{'study':42} {'runs':>7} {'estimate':>9} {'95 % interval':>17} {'real':>8} {'ratio':>6} {'spread':>6} "
          f"{'fixed':>8} {'ratio without':>13}")
    with tempfile.TemporaryDirectory() as tmp:
        for study in studies:
            estimates, lows, highs, reals, fixed, steady, runs = [], [], [], [], [], [], 0
            for _ in range(args.repetitions):
                dry = subprocess.run([args.gesweep, "run", str(study), "--dry-run", "--format", "json", "--threads",
                                      str(args.threads)], capture_output=True, text=True)
                if dry.returncode != 0:
                    raise RuntimeError(f"{study}: dry run exit {dry.returncode}: {dry.stderr.strip()}")
                report = json.loads(dry.stdout)
                runs = report["run_count"]
                estimates.append(report["estimated_seconds"])
                lows.append(report["estimated_seconds_interval"][0])
                highs.append(report["estimated_seconds_interval"][1] or float("inf"))
                fixed.append(report["fixed_seconds"] or 0.0)
                steady.append(steady_only(report, args.threads, cores))
                reals.append(real_run(args.gesweep, study, pathlib.Path(tmp) / "scratch.h5", args.threads))
            row = {"study": str(study.relative_to(ROOT)), "runs": runs, "estimate_s": statistics.median(estimates),
                   "interval_s": [statistics.median(lows), statistics.median(highs)],
                   "real_s": statistics.median(reals), "estimates_s": estimates, "reals_s": reals,
                   "fixed_s": statistics.median(fixed), "steady_only_s": statistics.median(steady)}
            row["ratio"] = row["estimate_s"] / row["real_s"] if row["real_s"] > 0 else float("nan")
            row["ratio_steady_only"] = row["steady_only_s"] / row["real_s"] if row["real_s"] > 0 else float("nan")
            row["spread"] = max(estimates) / min(estimates) if min(estimates) > 0 else float("nan")
            rows.append(row)
            print(f"{row['study']:42} {runs:7d} {row['estimate_s']:8.3g}s "
                  f"{row['interval_s'][0]:7.3g}-{row['interval_s'][1]:<7.3g}s {row['real_s']:7.3g}s "
                  f"{row['ratio']:6.2f} {row['spread']:6.2f} {row['fixed_s']:7.3g}s {row['ratio_steady_only']:13.2f}",
                  flush=True)
    within = [r for r in rows if abs(r["ratio"] - 1) <= 0.3]
    within_steady = [r for r in rows if abs(r["ratio_steady_only"] - 1) <= 0.3]
    load_after = os.getloadavg()
    print(f"# load average after: {load_after[0]:.2f} {load_after[1]:.2f} {load_after[2]:.2f}")
    print(f"# {len(within)} of {len(rows)} studies within 30 % ({len(within_steady)} without the per-sweep terms; "
          f"{args.threads} threads, {args.repetitions} repetitions)")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps({"threads": args.threads, "load_before": load_before,
                                                       "load_after": load_after, "rows": rows}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
