#!/usr/bin/python3
"""A signal reaches inside a long run (issue 13, docs/reliability.md "Signals").

    /usr/bin/python3 tests/reliability/signal_stop.py GESWEEP

1. `gesweep run` of four open-loop runs of 5e7 RK4 steps each (seconds of work per run, under the
   1e8 limit), one run per batch, two threads; SIGINT (then, on a fresh archive, SIGTERM) one second
   after the start. It must exit 130 (143) within 2 s of the signal, with a one-line message, and
   leave an archive that opens with h5py, holds no run marked complete that was not run to its end
   (complete runs only, every one equal to the uninterrupted result: the end time is the duration),
   and that `gesweep run --resume` finishes (exit 0) to every run ok.
2. `gesweep simulate` of 1e8 steps and `gesweep land` with a 1 ms largest step over 1e5 s (1e8 steps
   at least): SIGINT after a second; exit 130 within 2 s, nothing on stdout.
3. Set-up (issue 26, item 5): `simulate`, `land` and `run` of turbulent runs at the largest noise table
   allowed (1e7 samples), SIGTERM 0.15 s after the start, while the tables are built: exit 143 within
   1 s of the signal.
4. `gesweep run --dry-run` of the long study: returns within its 2 s budget plus start-up (bounded
   by a timeout of 30 s here: the time is not asserted, only that it ends and says "more than").
Timing: the 2 s bound is the issue's; the signal-to-exit time on an idle machine is ~0.1 s."""
import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

GESWEEP = os.path.abspath(sys.argv[1])
ROOT = pathlib.Path(__file__).resolve().parents[2]
ANCE = ROOT / "studies" / "aircraft" / "ance.toml"
# The bound on the time from the signal to the exit.
EXIT_WITHIN_S = 2.0
# How long after the start the signal comes (the runs are well under way, none finished).
SIGNAL_AFTER_S = 1.0
DURATION_S = 50000.0  # at step_s = 1e-3: 5e7 RK4 steps per run

STUDY = f'''format_version = 1
name = "long_runs"
aircraft = "{ANCE}"
[analyses.open_loop]
input = "none"
duration_s = {DURATION_S}
step_s = 0.001
[parameters]
speed_mps = 32.0208
[output]
chunk_runs = 1
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
values = [100.0, 200.0, 300.0, 400.0]
'''

# A stop during set-up (issue 26, item 5): the signal comes early, the exit within a second.
SETUP_SIGNAL_AFTER_S = 0.15
SETUP_EXIT_WITHIN_S = 1.0

TURBULENT_STUDY = f'''format_version = 1
name = "turbulent_set_up"
aircraft = "{ANCE}"
[analyses.open_loop]
input = "none"
duration_s = 1000.0
turbulence_sample_interval_s = 0.0001
[parameters]
speed_mps = 32.0208
turbulence = "dryden"
wind_20ft_mps = -7.7
[output]
chunk_runs = 1
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
values = [100.0, 200.0, 300.0, 400.0]
'''

failures = []


def interrupt(args, signum, expected_code, after_s=SIGNAL_AFTER_S, within_s=EXIT_WITHIN_S):
    """Starts gesweep, sends `signum` after `after_s`; returns (exit code, seconds from the signal to
    the exit, stdout, stderr). The exit must come within `within_s` of the signal."""
    process = subprocess.Popen([GESWEEP, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(after_s)
    if process.poll() is not None:
        out, err = process.communicate()
        failures.append(f"{args[0]} ended before the signal (exit {process.returncode}): {err.strip()[:300]}")
        return process.returncode, 0.0, out, err
    sent = time.monotonic()
    process.send_signal(signum)
    try:
        out, err = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        process.kill()
        out, err = process.communicate()
        failures.append(f"{args[0]}: still running 60 s after {signal.Signals(signum).name}")
        return None, 60.0, out, err
    elapsed = time.monotonic() - sent
    name = f"{' '.join(args[:1])} {signal.Signals(signum).name}"
    # A signal before the handlers are installed (still loading the study or the aircraft, under
    # load) ends the process as the signal's default does: the shell's 128 + signal too, nothing written.
    expected = {expected_code, -signum} if within_s == SETUP_EXIT_WITHIN_S else {expected_code}
    if process.returncode not in expected:
        failures.append(f"{name}: exit {process.returncode}, expected {expected_code}: {err.strip()[:300]}")
    if elapsed > within_s:
        failures.append(f"{name}: exited {elapsed:.2f} s after the signal, expected within {within_s} s")
    print(f"{name}: exit {process.returncode} {elapsed:.3f} s after the signal")
    return process.returncode, elapsed, out, err


def check_archive(path, expect_complete):
    with h5py.File(path, "r", swmr=True) as f:
        status = f["runs/status"][...]
        end_time = f["results/open_loop/end_time_s"][...]
        done = status != 0
        if expect_complete and not done.all():
            failures.append(f"{path}: {int((~done).sum())} runs pending after --resume")
        if not np.all(end_time[done] == DURATION_S):
            failures.append(f"{path}: a run marked complete did not fly to its end: {end_time[done]}")
        if not np.all(status[done] == 1):
            failures.append(f"{path}: statuses {status}")
        return int(done.sum())


with tempfile.TemporaryDirectory() as tmp:
    tmp = pathlib.Path(tmp)
    study = tmp / "long.toml"
    study.write_text(STUDY)
    for signum, code in ((signal.SIGINT, 130), (signal.SIGTERM, 143)):
        archive = tmp / f"{signal.Signals(signum).name}.h5"
        _, _, _, err = interrupt(["run", str(study), "-o", str(archive), "--threads", "2", "-q"], signum, code)
        if "continue with --resume" not in err:
            failures.append(f"run {signal.Signals(signum).name}: no '--resume' hint: {err.strip()[:300]}")
        complete = check_archive(archive, expect_complete=False)
        print(f"  {complete} of 4 runs complete at the signal")
        if signum == signal.SIGINT:
            resume = subprocess.run([GESWEEP, "run", str(study), "-o", str(archive), "--resume", "-q"],
                                    capture_output=True, text=True, timeout=600)
            if resume.returncode != 0:
                failures.append(f"--resume after SIGINT: exit {resume.returncode}: {resume.stderr.strip()[:300]}")
            check_archive(archive, expect_complete=True)

    _, _, out, _ = interrupt(["simulate", "--aircraft", str(ANCE), "--height-m", "100", "--speed-mps", "32",
                              "--input", "none", "--duration-s", "100000", "--dt-s", "0.001", "--summary-only"],
                             signal.SIGINT, 130)
    if out:
        failures.append(f"simulate wrote to stdout after a signal: {out[:200]!r}")
    # From 10 km: about 2 s of flight on a quiet machine, twice the signal's delay (from 5 km a quiet
    # machine landed in 1.0 s, before the signal).
    _, _, out, _ = interrupt(["land", "--aircraft", str(ANCE), "--time-limit-s", "100000", "--max-step-s", "0.001",
                              "--start-height-m", "10000", "--summary-only"], signal.SIGINT, 130)
    if out:
        failures.append(f"land wrote to stdout after a signal: {out[:200]!r}")

    # Issue 26, item 5: a stop during a run's set-up. A turbulent run at the largest noise table
    # allowed (1e7 samples: 1000 s at 1e-4 s) builds it before its first step; SIGTERM 0.15 s after the
    # start lands while it is built (or while the study is read), and must end it within 1 s.
    turbulent = ["--turbulence", "dryden", "--turbulence-sample-interval-s", "1e-4", "--wind-20ft-mps", "-7.7"]
    _, _, out, _ = interrupt(["simulate", "--aircraft", str(ANCE), "--height-m", "100", "--speed-mps", "32",
                              "--input", "none", "--duration-s", "1000", *turbulent, "--summary-only"],
                             signal.SIGTERM, 143, after_s=SETUP_SIGNAL_AFTER_S, within_s=SETUP_EXIT_WITHIN_S)
    if out:
        failures.append(f"simulate (set-up) wrote to stdout after a signal: {out[:200]!r}")
    interrupt(["land", "--aircraft", str(ANCE), "--time-limit-s", "1000", *turbulent, "--summary-only"],
              signal.SIGTERM, 143, after_s=SETUP_SIGNAL_AFTER_S, within_s=SETUP_EXIT_WITHIN_S)
    setup_study = tmp / "turbulent.toml"
    setup_study.write_text(TURBULENT_STUDY)
    archive = tmp / "turbulent.h5"
    interrupt(["run", str(setup_study), "-o", str(archive), "--threads", "2", "-q"], signal.SIGTERM, 143,
              after_s=SETUP_SIGNAL_AFTER_S, within_s=SETUP_EXIT_WITHIN_S)

    started = time.monotonic()
    dry = subprocess.run([GESWEEP, "run", str(study), "--dry-run"], capture_output=True, text=True, timeout=30)
    print(f"dry run of the long study: {time.monotonic() - started:.2f} s")
    if dry.returncode != 0 or "more than" not in dry.stdout:
        failures.append(f"dry run of the long study: exit {dry.returncode}: {dry.stdout.strip()[-300:]}")

for failure in failures:
    print("FAIL", failure)
sys.exit(1 if failures else 0)
