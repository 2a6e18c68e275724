#!/usr/bin/python3
"""The layout is the architecture (docs/architecture.md), and the product stands alone.

  layout_test.py REPO_ROOT

1. The folder table of docs/architecture.md lists exactly the folders under engine/.
2. Every `#include "engine/<folder>/..."` of an engine file names its own folder or one its folder
   reaches through the table's "depends on" column (direct dependencies, followed transitively):
   nothing includes a folder above it.
3. No tracked file of the product cites or reads the shared folder beside the clone, or cites MODEL.md / STYLE.md (the
   project's model is docs/model.md).
4. Only engine/archive includes HDF5 (hdf5.h or an H5*.h header).
5. No string literal of an engine file outside engine/cli names a CLI flag (`--word`): below the CLI
   errors name request fields and remedies, which engine/cli/request_names.cc spells as flags and
   hints (docs/architecture.md, "Names of the command line"). Comments are not checked: a comment
   may say which flag fills a field.
Lists every offender; exit 1 when there is one.
"""
import pathlib
import re
import subprocess
import sys

root = pathlib.Path(sys.argv[1]).resolve()
problems = []

# 1. The table.
table = {}
for line in (root / "docs" / "architecture.md").read_text().splitlines():
    m = re.match(r"\|\s*`engine/(\w+)`\s*\|[^|]*\|([^|]*)\|", line)
    if m:
        words = re.findall(r"[a-z]+", m.group(2).lower())
        table[m.group(1)] = set(words)
folders = {p.name for p in (root / "engine").iterdir() if p.is_dir()}
for f in sorted(folders - table.keys()):
    problems.append(f"engine/{f} exists but docs/architecture.md's table does not list it")
for f in sorted(table.keys() - folders):
    problems.append(f"docs/architecture.md lists engine/{f}, which does not exist")
for f, words in table.items():
    table[f] = folders if "everything" in words else {w for w in words if w in folders}


def reach(folder, seen=None):
    seen = set() if seen is None else seen
    for d in table.get(folder, ()):
        if d not in seen:
            seen.add(d)
            reach(d, seen)
    return seen


# 2. The includes.
include = re.compile(r'^\s*#\s*include\s*"engine/(\w+)/')
for folder in sorted(folders & table.keys()):
    allowed = reach(folder) | {folder}
    for path in sorted((root / "engine" / folder).rglob("*")):
        if path.suffix not in (".cc", ".h"):
            continue
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = include.match(line)
            if m and m.group(1) not in allowed:
                problems.append(f"{path.relative_to(root)}:{number}: engine/{folder} includes engine/{m.group(1)}, "
                                f"which it does not depend on (docs/architecture.md): {line.strip()}")

# 4. HDF5 stays in engine/archive.
hdf5_include = re.compile(r'^\s*#\s*include\s*[<"](hdf5\.h|H5\w*\.h)[>"]')
for path in sorted((root / "engine").rglob("*")):
    if path.suffix not in (".cc", ".h") or path.parent.name == "archive":
        continue
    for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
        if hdf5_include.match(line):
            problems.append(f"{path.relative_to(root)}:{number}: includes HDF5 outside engine/archive: {line.strip()}")

# 5. No CLI flag below engine/cli: string literals only (comments, char literals and code skipped).
def string_literals(text):
    """(line, literal body) of each string literal of C++ source `text`, raw strings included."""
    i, n, line = 0, len(text), 1
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif text.startswith("//", i):
            i = text.find("\n", i)
            i = n if i < 0 else i
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            line += text.count("\n", i, end)
            i = end
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            open_paren = text.find("(", i + 2)
            delimiter = text[i + 2:open_paren]
            end = text.find(")" + delimiter + '"', open_paren)
            end = n if end < 0 else end
            yield line, text[open_paren + 1:end]
            line += text.count("\n", i, end)
            i = end + len(delimiter) + 2
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            if c == '"':
                yield line, text[i + 1:j]
            i = j + 1
        else:
            i += 1


flag = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")
for path in sorted((root / "engine").rglob("*")):
    if path.suffix not in (".cc", ".h") or "cli" in path.relative_to(root / "engine").parts[:1]:
        continue
    for number, literal in string_literals(path.read_text(errors="replace")):
        m = flag.search(literal)
        if m:
            problems.append(f"{path.relative_to(root)}:{number}: names the CLI flag {m.group(0)} below engine/cli "
                            f"(name the request field or a remedy; engine/cli/request_names.cc spells it): "
                            f'"{literal[:80]}"')

# 3. Standing alone: every tracked file (this test names the patterns, so it is left out).
tracked = subprocess.run(["git", "-C", str(root), "ls-files"], capture_output=True, text=True)
files = tracked.stdout.split() if tracked.returncode == 0 else [
    str(p.relative_to(root)) for p in root.rglob("*") if p.is_file() and ".git" not in p.parts
    and not p.parts[len(root.parts)].startswith("build")]
foreign = re.compile(r"\.\./shared\b|\bMODEL\.md\b|\bSTYLE\.md\b")
this = pathlib.Path(__file__).resolve()
for name in files:
    path = root / name
    if path.resolve() == this or not path.is_file():
        continue
    try:
        text = path.read_text()
    except (UnicodeDecodeError, OSError):
        continue
    for number, line in enumerate(text.splitlines(), 1):
        if foreign.search(line):
            problems.append(f"{name}:{number}: cites a file outside the repository: {line.strip()[:120]}")

if problems:
    print(f"{len(problems)} layout problems:")
    for p in problems:
        print("  " + p)
    sys.exit(1)
print(f"layout: {len(folders)} engine folders as docs/architecture.md lists them; includes point down; "
      f"only engine/archive includes HDF5; no CLI flag below engine/cli; {len(files)} tracked files cite nothing outside the repository")
