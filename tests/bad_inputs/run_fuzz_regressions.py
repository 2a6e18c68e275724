#!/usr/bin/python3
"""Replays the inputs on which libFuzzer's fuzz_study target once failed (tests/bad_inputs/fuzz_regressions,
copied from build-fuzz/crashes/fuzz_study; docs/reliability.md, "Fuzzing") through the real binary:
`gesweep run FILE -o OUT --dry-run` must either accept the study (exit 0) or refuse it with exit 2 and
exactly one line on stderr, and must never write an archive. Every input once broke that contract
(a multi-line message); this keeps them fixed in every build, not only in the clang fuzz build.
Usage: run_fuzz_regressions.py GESWEEP"""
import pathlib
import subprocess
import sys
import tempfile

binary = sys.argv[1]
folder = pathlib.Path(__file__).resolve().parent / "fuzz_regressions"
cases = sorted(folder.glob("*.toml"))
failures = []
for case in cases:
    with tempfile.TemporaryDirectory() as out:
        result = subprocess.run([binary, "run", str(case), "-o", f"{out}/out.h5", "--dry-run"],
                                capture_output=True, text=True, timeout=60)
        lines = result.stderr.strip().splitlines()
        if result.returncode == 2 and len(lines) != 1:
            failures.append(f"{case.name}: exit 2 with {len(lines)} stderr lines, expected one: {result.stderr!r}")
        elif result.returncode not in (0, 2):
            failures.append(f"{case.name}: exit {result.returncode}, expected 0 or 2: {result.stderr[:300]!r}")
        if any(pathlib.Path(out).iterdir()):
            failures.append(f"{case.name}: left {sorted(p.name for p in pathlib.Path(out).iterdir())}")
for failure in failures:
    print("FAIL", failure)
print(f"{len(cases)} fuzz regression inputs, {len(cases) - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures or not cases else 0)
