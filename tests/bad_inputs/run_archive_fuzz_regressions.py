#!/usr/bin/python3
"""Replays the inputs on which libFuzzer's fuzz_archive target once failed (tests/bad_inputs/
archive_fuzz_regressions; docs/reliability.md, "Fuzzing") through the real binary, as archives:
every reader -- query (rows and --describe), boundary --archive --no-write, sensitivity --no-write,
merge, report -- must give exit 0, 3 (runs without a value), or 2 (bad input) / 1 (I/O) with exactly
one line on stderr; never a signal; and nothing may be left behind (no merged archive, no report
directory, no lock file).

Each file is a fuzz input: its first byte is the target's mode (even: the rest is the file's bytes);
an input of the builder mode (odd) is kept as the HDF5 file it built, written with
GESWEEP_FUZZ_ARCHIVE_OUT=FILE build-fuzz/tests/fuzz/fuzz_archive INPUT and prefixed with a zero byte.
Usage: run_archive_fuzz_regressions.py GESWEEP"""
import os
import pathlib
import subprocess
import sys
import tempfile

binary = sys.argv[1]
folder = pathlib.Path(__file__).resolve().parent / "archive_fuzz_regressions"
# A sanitized gesweep (./scripts/test --sanitize) checks for leaks at exit; leaks inside libhdf5 itself
# on a damaged file are suppressed by HDF5 function (tests/fuzz/hdf5_lsan.supp, the file fuzz_archive
# runs with), which only the slow unwinder finds in a leak's stack: libhdf5 has no frame pointers.
env = dict(os.environ)
if b"__asan_init" in pathlib.Path(binary).read_bytes():
    supp = pathlib.Path(__file__).resolve().parents[1] / "fuzz" / "hdf5_lsan.supp"
    env["LSAN_OPTIONS"] = ":".join(filter(None, [f"suppressions={supp}:print_suppressions=0", env.get("LSAN_OPTIONS")]))
    env["ASAN_OPTIONS"] = ":".join(filter(None, ["fast_unwind_on_malloc=0", env.get("ASAN_OPTIONS")]))
cases = sorted(p for p in folder.iterdir() if p.is_file())
readers = [["query", "{a}"], ["query", "{a}", "--describe"], ["boundary", "--archive", "{a}", "--no-write"],
           ["sensitivity", "{a}", "--output", "value", "--no-write"], ["merge", "{a}", "-o", "{out}/merged.h5"],
           ["report", "{a}", "-o", "{out}/report", "--quiet"]]
failures = []
for case in cases:
    data = case.read_bytes()
    if not data or data[0] % 2:
        failures.append(f"{case.name}: a builder-mode input; keep the file it builds instead (see the docstring)")
        continue
    with tempfile.TemporaryDirectory() as out:
        archive = pathlib.Path(out) / "archive.h5"
        archive.write_bytes(data[1:])
        for reader in readers:
            args = [a.replace("{a}", str(archive)).replace("{out}", out) for a in reader]
            result = subprocess.run([binary, *args], capture_output=True, text=True, timeout=120, env=env)
            lines = result.stderr.strip().splitlines()
            name = f"{case.name}: {reader[0]}{' ' + reader[2] if reader[0] == 'query' and len(reader) > 2 else ''}"
            if result.returncode < 0 or result.returncode not in (0, 1, 2, 3):
                failures.append(f"{name}: exit {result.returncode}: {result.stderr[-300:]!r}")
            elif result.returncode in (1, 2) and len(lines) != 1:
                failures.append(f"{name}: exit {result.returncode} with {len(lines)} stderr lines: {result.stderr[:300]!r}")
            left = sorted(p.name for p in pathlib.Path(out).iterdir() if p.name != "archive.h5")
            if left and result.returncode != 0:
                failures.append(f"{name}: left {left}")
            for p in pathlib.Path(out).iterdir():
                if p.name != "archive.h5":
                    subprocess.run(["rm", "-rf", str(p)])
            archive.write_bytes(data[1:])  # as it was, whatever a reader did
for failure in failures:
    print("FAIL", failure)
print(f"{len(cases)} archive fuzz regression inputs, {len(failures)} failures")
sys.exit(1 if failures or not cases else 0)
