#!/usr/bin/python3
"""Every aircraft file in studies/aircraft validates against schemas/aircraft.schema.json, and the
schema rejects a file with a misspelt key (so the test can fail)."""
import json
import pathlib
import sys
import tomllib

import jsonschema

schema = json.loads(pathlib.Path("schemas/aircraft.schema.json").read_text())
jsonschema.Draft202012Validator.check_schema(schema)
validator = jsonschema.Draft202012Validator(schema)
files = sorted(pathlib.Path("studies/aircraft").glob("*.toml"))
failures = 0
for path in files:
    errors = list(validator.iter_errors(tomllib.loads(path.read_text())))
    for e in errors:
        print(f"{path}: {'.'.join(map(str, e.path))}: {e.message}")
    failures += len(errors)
bad = tomllib.loads(files[0].read_text())
bad["geometry"]["wingspam_m"] = bad["geometry"].pop("wingspan_m")
if validator.is_valid(bad):
    print("schema accepted a misspelt key")
    failures += 1
print(f"{len(files)} aircraft files checked, {failures} problems")
sys.exit(1 if failures or not files else 0)
