"""The column manifest (schemas/columns.json, the output of `gesweep columns --json`) for scripts.

Scripts ask it for an archive path instead of spelling one out, so a column that an analysis renames
or drops fails here, with one line naming it, and not as a KeyError deep inside h5py:

    import columns
    columns.path("modes", "stability_margin_per_s")           # "results/modes/stability_margin_per_s"
    columns.path("open_loop", "height_m", series=True)        # "series/open_loop/height_m"
    columns.units("open_loop", "min_height_m")                # "m"
    columns.levels("landing", "outcome")                      # ["landed", "no_touchdown", ...]
    columns.time_axis("landing")                              # "series/landing/time_s"

An analysis's results and series are asked for apart (`series=True`): the two groups may hold the same
name. Set GESWEEP_COLUMNS_MANIFEST to read another manifest (a test of a new analysis, say).
Reference: schemas/archive.md; regenerate the manifest with `gesweep columns --json > schemas/columns.json`.
"""

import functools
import json
import os

MANIFEST_PATH = os.environ.get("GESWEEP_COLUMNS_MANIFEST") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "schemas", "columns.json")
# The manifest's own layout version this module reads (`format_version` of columns.json).
MANIFEST_FORMAT_VERSION = 1
# The roles of rated columns (`gesweep columns`: an int8 column whose levels begin "level 1"; the one
# named "level" is its analysis's overall rating).
RATING, OVERALL_RATING = "rating", "overall_rating"


# The archive's groups of per-run datasets, as the manifest names them (a column's "group"; the first
# part of a runs/ or design/ path). A design dataset is DESIGN_GROUP/<parameter> for each name of the
# archive's /design@parameters.
RUNS_GROUP, DESIGN_GROUP, RESULTS_GROUP, SERIES_GROUP = "runs", "design", "results", "series"


class UnknownColumn(LookupError):
    """A script asked for an analysis or column the manifest does not have."""


@functools.cache
def manifest():
    """The manifest as parsed JSON (read once)."""
    try:
        with open(MANIFEST_PATH, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as error:
        raise UnknownColumn(f"{MANIFEST_PATH}: cannot read the column manifest ({error}); regenerate it with "
                            f"`gesweep columns --json > schemas/columns.json`") from None
    if data.get("format") != "gesweep-columns" or data.get("format_version") != MANIFEST_FORMAT_VERSION:
        raise UnknownColumn(f"{MANIFEST_PATH}: not a gesweep column manifest of format {MANIFEST_FORMAT_VERSION}")
    return data


def analyses():
    """The names of every analysis, in archive column order."""
    return [a["name"] for a in manifest()["analyses"]]


def analysis(name):
    """The manifest entry of an analysis (name, description, columns, time_axes, ...)."""
    for entry in manifest()["analyses"]:
        if entry["name"] == name:
            return entry
    raise UnknownColumn(f"{MANIFEST_PATH}: no analysis '{name}' (analyses: {', '.join(analyses())})")


def column(analysis_name, name, series=False):
    """The manifest entry of one column: path, units, description, type, width, levels, ...; raises
    UnknownColumn naming the analysis, the column and the names it does have."""
    group = SERIES_GROUP if series else RESULTS_GROUP
    entry = analysis(analysis_name)
    for c in entry["columns"]:
        if c["group"] == group and c["name"] == name:
            return c
    known = [c["name"] for c in entry["columns"] if c["group"] == group]
    raise UnknownColumn(f"{MANIFEST_PATH}: analysis '{analysis_name}' has no {group} column '{name}' "
                        f"({group} columns: {', '.join(known) or 'none'})")


def path(analysis_name, name, series=False):
    """The archive path of a result ("results/<analysis>/<name>") or, with series=True, of a time
    series ("series/<analysis>/<name>")."""
    return column(analysis_name, name, series)["path"]


def units(analysis_name, name, series=False):
    return column(analysis_name, name, series)["units"]


def description(analysis_name, name, series=False):
    return column(analysis_name, name, series)["description"]


def levels(analysis_name, name, series=False):
    """The names of an integer column's codes (0, 1, ...); [] when it has none."""
    return list(column(analysis_name, name, series)["levels"])


def time_axis(analysis_name):
    """The path of an analysis's shared time axis (its series' `time_axis`)."""
    axes = analysis(analysis_name)["time_axes"]
    if len(axes) != 1:
        raise UnknownColumn(f"{MANIFEST_PATH}: analysis '{analysis_name}' has {len(axes)} time axes, not one")
    return axes[0]["path"]


def design_path(parameter):
    """The archive path of a swept parameter ("design/<parameter>")."""
    for entry in manifest()["design"]:
        if entry["name"] == parameter:
            return entry["path"]
    raise UnknownColumn(f"{MANIFEST_PATH}: no design parameter '{parameter}'")


def runs_path(name):
    """The archive path of a bookkeeping dataset ("status" gives "runs/status")."""
    for entry in manifest()["runs"]:
        if entry["path"].split("/")[-1] == name:
            return entry["path"]
    raise UnknownColumn(f"{MANIFEST_PATH}: no runs dataset '{name}'")


def runs_paths():
    """The paths of every bookkeeping dataset (runs/index, runs/id, runs/status, runs/message)."""
    return tuple(entry["path"] for entry in manifest()["runs"])


def ratings():
    """Every analysis with rated columns, as (analysis entry, overall column or None, [part columns]),
    in manifest order. A part's name is that of its column without the suffix "_level"."""
    out = []
    for entry in manifest()["analyses"]:
        overall = [c for c in entry["columns"] if c["role"] == OVERALL_RATING]
        parts = [c for c in entry["columns"] if c["role"] == RATING]
        if overall or parts:
            out.append((entry, overall[0] if overall else None, parts))
    return out


def groups():
    """The top-level groups of per-run datasets ("runs/", "design/", "results/", "series/")."""
    found = {c["path"].split("/")[0] + "/": None for c in manifest()["runs"] + manifest()["design"]}
    for entry in manifest()["analyses"]:
        found.update({c["group"] + "/": None for c in entry["columns"]})
    return tuple(found)
