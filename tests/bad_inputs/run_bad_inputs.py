#!/usr/bin/python3
"""Runs the hostile-input corpus against the real gesweep binary.

tests/bad_inputs/aircraft/NAME.toml   aircraft files, loaded by `gesweep modes --aircraft NAME.toml`
tests/bad_inputs/study/NAME.toml      study files, run by `gesweep run NAME.toml -o <tmp>/out.h5`
NAME.expect                           a fragment the one-line error message must contain

Every case must exit 2, print exactly one line on stderr containing the fragment, and leave no file
in the output directory. Cases that need setup (unreadable paths, symlink loops, ...) are in
SPECIAL_CASES below."""
import os
import pathlib
import subprocess
import sys
import tempfile

GESWEEP = os.path.abspath(sys.argv[1])
ROOT = pathlib.Path(__file__).resolve().parent
failures = []
count = 0


def check(name, args, fragment, out_dir):
    global count
    count += 1
    result = subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=120)
    lines = result.stderr.strip().splitlines()
    problems = []
    if result.returncode != 2:
        problems.append(f"exit {result.returncode}, expected 2")
    if len(lines) != 1:
        problems.append(f"{len(lines)} stderr lines, expected 1")
    if not any(fragment in line for line in lines):
        problems.append(f"no line contains {fragment!r}")
    left = sorted(p.name for p in pathlib.Path(out_dir).iterdir())
    if left:
        problems.append(f"left files behind: {left}")
    if problems:
        failures.append(f"{name}: {'; '.join(problems)}\n    stderr: {result.stderr.strip()[:400]}")


def corpus(kind, make_args):
    folder = ROOT / kind
    if not folder.is_dir():
        return
    for case in sorted(folder.glob("*.toml")):
        fragment = case.with_suffix(".expect").read_text().strip()
        with tempfile.TemporaryDirectory() as out_dir:
            check(f"{kind}/{case.name}", make_args(str(case), out_dir), fragment, out_dir)


corpus("aircraft", lambda path, out: ["modes", "--aircraft", path, "--speed-mps", "30", "--table-heights"])
corpus("study", lambda path, out: ["run", path, "-o", os.path.join(out, "out.h5")])


def special_aircraft_cases():
    ance = pathlib.Path("studies/aircraft/ance.toml").resolve()
    with tempfile.TemporaryDirectory() as tmp, tempfile.TemporaryDirectory() as out:
        tmp = pathlib.Path(tmp)
        loop_a, loop_b = tmp / "loop_a.toml", tmp / "loop_b.toml"
        loop_a.symlink_to(loop_b)
        loop_b.symlink_to(loop_a)
        check("aircraft symlink loop", ["modes", "--aircraft", str(loop_a), "--speed-mps", "30", "--table-heights"],
              "symbolic links", out)
        check("aircraft is a directory", ["modes", "--aircraft", str(tmp), "--speed-mps", "30", "--table-heights"],
              "found a directory", out)
        if os.geteuid() != 0:  # root reads any file, so an unreadable file cannot be made as root
            locked = tmp / "locked.toml"
            locked.write_text(ance.read_text())
            locked.chmod(0)
            check("aircraft unreadable", ["modes", "--aircraft", str(locked), "--speed-mps", "30", "--table-heights"],
                  "cannot open", out)


special_aircraft_cases()

for failure in failures:
    print("FAIL", failure)
print(f"{count} hostile inputs, {count - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures or count == 0 else 0)
