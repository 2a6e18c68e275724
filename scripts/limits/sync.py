#!/usr/bin/python3
"""Writes the limits table into schemas/study.schema.json and docs/limits.md.

    /usr/bin/python3 scripts/limits/sync.py build/gesweep      # rewrites both in place
    /usr/bin/python3 scripts/limits/sync.py build/gesweep --check

docs/limits.md: everything after its "## The table" heading is `gesweep limits --format markdown`.

The table (engine/common/input_limits.cc, printed by `gesweep limits --format json`) is the one source
of every range; the schema states the same bounds at the places tests/sweep/schema_sync_test.cc checks:
every real parameter, every analysis setting named <analysis>.<key>, the tolerances of open_loop and
landing, landing.design_speed_mps, boundary's lower/upper_height_m and output.output_dt_s. --check
prints the differences and exits 1 when there are any, without writing."""
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCHEMA = ROOT / "schemas" / "study.schema.json"
DOC = ROOT / "docs" / "limits.md"
DOC_HEADING = "## The table\n\n"
# The catalogue's parameters that take their range from a family entry of the table.
FAMILIES = {"scale.": "scale_factor", "q_weights.": "q_weights", "x": "verification_input"}


def number(value):
    """A bound as the schema writes it: whole numbers without a fraction."""
    return int(value) if float(value).is_integer() and abs(value) < 1e15 else value


def bounds(limit):
    out = {}
    out["exclusiveMinimum" if limit["minimum_exclusive"] else "minimum"] = number(limit["minimum"])
    if not limit["allows_infinity"]:  # JSON has no inf: a quantity that takes inf states no maximum
        out["exclusiveMaximum" if limit["maximum_exclusive"] else "maximum"] = number(limit["maximum"])
    return out


def places(schema, limits):
    """(schema entry, limit) pairs."""
    parameters = schema["properties"]["parameters"]["properties"]
    analyses = schema["properties"]["analyses"]["properties"]
    for name, entry in parameters.items():
        if entry.get("type") != "number":
            continue
        limit = limits.get(name)
        for prefix, family in FAMILIES.items():
            if limit is None and name.startswith(prefix) and (prefix != "x" or name[1:].isdigit()):
                limit = limits[family]
        if limit is None:
            raise SystemExit(f"sync: parameters.{name} has no entry in the limits table")
        yield entry, limit
    for name, limit in limits.items():
        analysis, _, key = name.partition(".")
        if key and analysis in analyses and key in analyses[analysis]["properties"]:
            yield analyses[analysis]["properties"][key], limit
    for analysis in ("open_loop", "landing"):
        for key in ("relative_tolerance", "absolute_tolerance"):
            yield analyses[analysis]["properties"][key], limits[key]
    yield analyses["landing"]["properties"]["design_speed_mps"], limits["speed_mps"]
    yield analyses["boundary"]["properties"]["lower_height_m"], limits["height_m"]
    yield analyses["boundary"]["properties"]["upper_height_m"], limits["height_m"]
    yield schema["properties"]["output"]["properties"]["output_dt_s"], limits["output_dt_s"]


def main():
    gesweep = sys.argv[1]
    check = "--check" in sys.argv[2:]
    table = json.loads(subprocess.run([gesweep, "limits", "--format", "json"], check=True, capture_output=True,
                                      text=True).stdout)
    limits = {limit["name"]: limit for limit in table["limits"]}
    schema = json.loads(SCHEMA.read_text())
    differences = 0
    for entry, limit in places(schema, limits):
        wanted = bounds(limit)
        current = {k: entry[k] for k in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum") if k in entry}
        if current != wanted:
            differences += 1
            print(f"{limit['name']}: schema {current} -> table {wanted}")
            for k in current:
                del entry[k]
            entry.update(wanted)
    markdown = subprocess.run([gesweep, "limits", "--format", "markdown"], check=True, capture_output=True,
                              text=True).stdout
    doc = DOC.read_text()
    head = doc.split(DOC_HEADING, 1)[0] if DOC_HEADING in doc else doc.rstrip("\n") + "\n\n"
    new_doc = head + DOC_HEADING + markdown
    if new_doc != doc:
        differences += 1
        print(f"{DOC}: the table differs from gesweep limits --format markdown")
    if check:
        return 1 if differences else 0
    SCHEMA.write_text(json.dumps(schema, indent=2, ensure_ascii=False) + "\n")
    DOC.write_text(new_doc)
    print(f"sync: {differences} differences written ({SCHEMA.name}, {DOC.name})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
