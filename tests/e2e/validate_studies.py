#!/usr/bin/python3
"""Validates every study file under studies/ (except studies/aircraft) against
schemas/study.schema.json with tomllib + jsonschema, and checks that the schema rejects a few
known-bad studies (so this test can fail). Run from the repository root or give it as argv[1]."""
import pathlib
import sys
import tomllib

import jsonschema

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
schema = __import__("json").loads((root / "schemas" / "study.schema.json").read_text())
jsonschema.Draft202012Validator.check_schema(schema)
validator = jsonschema.Draft202012Validator(schema)

failures = 0
studies = sorted(p for p in (root / "studies").rglob("*.toml") if "aircraft" not in p.relative_to(root / "studies").parts)
if not studies:
    print("no study files found under", root / "studies")
    sys.exit(1)
for path in studies:
    with open(path, "rb") as f:
        study = tomllib.load(f)
    errors = sorted(validator.iter_errors(study), key=lambda e: list(e.path))
    for error in errors:
        print(f"{path.relative_to(root)}: {'.'.join(map(str, error.path)) or '(root)'}: {error.message}")
    failures += bool(errors)
    if not errors:
        print(f"ok   {path.relative_to(root)}")

# The schema must refuse these.
bad = {
    "unknown top-level key": 'format_version = 1\nanalyses.modes = {}\ntitle = "x"\n',
    "misspelt parameter": 'format_version = 1\n[analyses.modes]\n[parameters]\nheigth_m = 2\n',
    "unknown analysis": 'format_version = 1\n[analyses.mode]\n',
    "grid axis without values": 'format_version = 1\n[analyses.modes]\n[design]\nkind = "grid"\n[[design.parameter]]\nname = "height_m"\n',
    "sobol over a choice": 'format_version = 1\n[analyses.modes]\n[design]\nkind = "sobol"\nbase_samples = 4\n'
                           '[[design.parameter]]\nname = "cdh"\nuniform = [0, 1]\n',
    "odd morris levels": 'format_version = 1\n[analyses.ishigami]\n[design]\nkind = "morris"\ntrajectories = 2\nlevels = 3\n'
                         'seed = 1\n[[design.parameter]]\nname = "x1"\nuniform = [0, 1]\n',
    "wrong format version": 'format_version = 2\n[analyses.modes]\n',
}
for name, text in bad.items():
    if validator.is_valid(tomllib.loads(text)):
        print(f"schema accepted a bad study ({name})")
        failures += 1
print(f"{len(studies)} study files, {failures} failure(s)")
sys.exit(1 if failures else 0)
