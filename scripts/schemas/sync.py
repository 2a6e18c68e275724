#!/usr/bin/python3
"""The per-analysis part of schemas/study.schema.json, generated from the column manifest.

schemas/columns.json (`gesweep columns --json`) lists every registered analysis in the registry's
order, with its description and, when its settings are described once (engine/common/describe.h),
the JSON Schema of each study key of [analyses.<name>] (`settings`). This script writes
`properties.analyses.properties` of schemas/study.schema.json from it: one entry per analysis, in
that order, with that description and those properties. An analysis whose settings are still read by
hand (`settings` null: engine/cli/columns_command.cc, kSettingsByHand) keeps its entry as written
in the schema but for the description. Nothing else of the schema is touched.

After adding or changing an analysis (docs/sweep.md, "Adding an analysis"):

    ./build/gesweep columns --json > schemas/columns.json
    python3 scripts/schemas/sync.py

`--check` writes nothing and exits 1 naming what differs (ctest schemas.study_analyses).
"""
import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCHEMA = os.path.join(ROOT, "schemas", "study.schema.json")
MANIFEST = os.path.join(ROOT, "schemas", "columns.json")
NO_SETTINGS = " No settings."


def analyses_part(manifest, current):
    """The `analyses` properties the manifest gives; `current` supplies hand-written settings."""
    out = {}
    for analysis in manifest["analyses"]:
        name = analysis["name"]
        settings = analysis["settings"]
        if settings is None:  # read by hand: the entry as written, with the registry's description
            if name not in current:
                raise SystemExit(f"schemas/study.schema.json: analysis '{name}' reads its settings by hand "
                                 "(not described): write its entry in the schema first")
            out[name] = dict(current[name], description=analysis["description"])
            continue
        description = analysis["description"] + (NO_SETTINGS if not settings else "")
        out[name] = {"type": "object", "description": description, "additionalProperties": False,
                     "properties": settings}
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if the schema differs")
    args = parser.parse_args()
    with open(MANIFEST, encoding="utf-8") as f:
        manifest = json.load(f)
    with open(SCHEMA, encoding="utf-8") as f:
        text = f.read()
    schema = json.loads(text)
    analyses = schema["properties"]["analyses"]["properties"]
    generated = analyses_part(manifest, analyses)
    schema["properties"]["analyses"]["properties"] = generated
    new_text = json.dumps(schema, indent=2, ensure_ascii=False) + "\n"
    if args.check:
        if new_text == text:
            return 0
        changed = sorted(set(analyses) ^ set(generated)) + [
            name for name in generated if name in analyses and analyses[name] != generated[name]]
        order = list(analyses) != list(generated)
        print(f"schemas/study.schema.json is not what schemas/columns.json gives (analyses differing: "
              f"{', '.join(changed) or 'none'}{'; order differs' if order else ''}): run "
              "`./build/gesweep columns --json > schemas/columns.json && python3 scripts/schemas/sync.py`",
              file=sys.stderr)
        return 1
    if new_text != text:
        with open(SCHEMA + ".partial", "w", encoding="utf-8") as f:
            f.write(new_text)
        os.replace(SCHEMA + ".partial", SCHEMA)
    return 0


if __name__ == "__main__":
    sys.exit(main())
