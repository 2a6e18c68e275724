#!/usr/bin/python3
"""The engine is clean under the repository's .clang-tidy (docs/reliability.md, "Static checks").

  clang_tidy_check.py REPO_ROOT BUILD_DIR [JOBS]

Runs clang-tidy (Debian's; scripts/lib/setup.sh installs it) with the checks of .clang-tidy over
every tracked .cc file of engine/ (headers through HeaderFilterRegex), using BUILD_DIR's
compile_commands.json, JOBS files at a time (default 2). Lists every finding as
FILE:LINE:COL: warning: ... [check]; exit 1 when there is one.
"""
import concurrent.futures
import pathlib
import re
import shutil
import subprocess
import sys

root = pathlib.Path(sys.argv[1]).resolve()
build = pathlib.Path(sys.argv[2]).resolve()
jobs = int(sys.argv[3]) if len(sys.argv) > 3 else 2
tidy = shutil.which("clang-tidy") or shutil.which("clang-tidy-14")
if tidy is None:
    sys.exit("clang-tidy not found: apt-get install clang-tidy")
if not (build / "compile_commands.json").is_file():
    sys.exit(f"{build}/compile_commands.json is missing: configure with CMAKE_EXPORT_COMPILE_COMMANDS=ON")
tracked = subprocess.run(["git", "-C", str(root), "ls-files", "--", "engine"], capture_output=True, text=True)
if tracked.returncode == 0:
    files = [name for name in tracked.stdout.split() if name.endswith(".cc")]
else:
    files = [str(p.relative_to(root)) for p in (root / "engine").rglob("*.cc")]

finding = re.compile(r"^(/[^:]+):(\d+):(\d+): (warning|error): (.*)$", re.M)


def run(name):
    done = subprocess.run([tidy, "-p", str(build), "--quiet", str(root / name)], cwd=root,
                          capture_output=True, text=True)
    return name, done.returncode, done.stdout + done.stderr


found = set()
failed = []
with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
    for name, code, output in pool.map(run, sorted(files)):
        hits = finding.findall(output)
        for path, line, col, kind, text in hits:
            try:
                shown = str(pathlib.Path(path).resolve().relative_to(root))
            except ValueError:
                continue  # a system header: not ours
            found.add((shown, int(line), int(col), kind, text))
        if code != 0 and not hits:
            failed.append(f"{name}: clang-tidy exited {code}: {output.strip()[:300]}")

for f in failed:
    print(f)
if found:
    print(f"{len(found)} clang-tidy findings in the engine ({len(files)} files):")
    for path, line, col, kind, text in sorted(found):
        print(f"  {path}:{line}:{col}: {kind}: {text}")
if found or failed:
    sys.exit(1)
print(f"clang-tidy: {len(files)} engine files are clean under .clang-tidy")
