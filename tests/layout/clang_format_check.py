#!/usr/bin/python3
"""Every tracked C++ file of engine/ and tests/ is clean under the repository's .clang-format.

  clang_format_check.py REPO_ROOT [CLANG_FORMAT]

Runs `clang-format --dry-run -Werror` (Debian's clang-format; the package list of scripts/lib/setup.sh
installs it) over each tracked .h/.cc file under engine/ and tests/, and lists the files it would change.
Exit 1 when there is one; to clean a file, `clang-format -i FILE` (or `git clang-format` for the lines
a change touched).
"""
import pathlib
import re
import shutil
import subprocess
import sys

root = pathlib.Path(sys.argv[1]).resolve()
clang_format = sys.argv[2] if len(sys.argv) > 2 else (shutil.which("clang-format") or "clang-format")
tracked = subprocess.run(["git", "-C", str(root), "ls-files", "--", "engine", "tests"],
                         capture_output=True, text=True)
if tracked.returncode == 0:
    files = [name for name in tracked.stdout.split() if name.endswith((".h", ".cc"))]
else:  # not a git checkout (an exported tree): every file on disk
    files = [str(p.relative_to(root)) for top in ("engine", "tests") for p in (root / top).rglob("*")
             if p.suffix in (".h", ".cc")]
if not files:
    print("clang-format: no C++ file found under engine/ or tests/")
    sys.exit(1)

# One clang-format process for all files (one per file costs seconds on a busy machine); each
# replacement it would make is reported as "FILE:LINE:COL: error: code should be clang-formatted".
run = subprocess.run([clang_format, "--dry-run", "-Werror", "--style=file", *sorted(files)], cwd=root,
                     capture_output=True, text=True)
flagged = re.compile(r"^(.+?):\d+:\d+: (?:error|warning): code should be clang-formatted", re.M)
unclean = sorted(set(flagged.findall(run.stderr)))
if run.returncode != 0 and not unclean:
    print(f"clang-format failed (exit {run.returncode}):\n{run.stderr.strip()}")
    sys.exit(1)

if unclean:
    print(f"{len(unclean)} of {len(files)} C++ files are not clang-format clean "
          f"(clang-format -i FILE, or git clang-format for changed lines):")
    for name in unclean:
        print("  " + name)
    sys.exit(1)
print(f"clang-format: {len(files)} C++ files of engine/ and tests/ are clean")
