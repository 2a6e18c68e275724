#!/usr/bin/python3
"""The archive owns HDF5 (docs/architecture.md): no file of the engine outside engine/archive
includes an HDF5 header (hdf5.h, H5*.h, or engine/archive/hdf5_util.h, which includes it) or calls
the HDF5 C API (H5*(...), hid_t). Lists every offender with its line; exit 1 when there is one.

  hdf5_ownership_test.py REPO_ROOT

The engine's public archive headers may still include HDF5 for their own members; what this
checks is that no code outside engine/archive uses it. Tests (tests/) use HDF5 directly on purpose:
it is their independent oracle.
"""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1]).resolve()
engine = root / "engine"
patterns = [
    ("includes an HDF5 header", re.compile(r'#\s*include\s*[<"](?:hdf5\.h|H5\w*\.h|engine/archive/hdf5_util\.h)[>"]')),
    ("calls the HDF5 C API", re.compile(r"\bH5[A-Z]\w*\s*\(")),
    ("uses an HDF5 identifier", re.compile(r"\bhid_t\b|\bhsize_t\b|\bH5[PST]_[A-Z_]+\b")),
]
offenders = []
for path in sorted(engine.rglob("*")):
    if path.suffix not in (".cc", ".h", ".cpp", ".hpp") or (engine / "archive") in path.parents:
        continue
    for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
        code = line.split("//", 1)[0]
        for what, pattern in patterns:
            if pattern.search(code):
                offenders.append(f"{path.relative_to(root)}:{number}: {what}: {line.strip()}")
                break
if offenders:
    files = sorted({o.split(":", 1)[0] for o in offenders})
    print(f"HDF5 outside engine/archive: {len(offenders)} lines in {len(files)} files:")
    for o in offenders:
        print("  " + o)
    sys.exit(1)
print("HDF5 is used only inside engine/archive")
