"""The column manifest (the output of `gesweep columns --json`) for scripts.

Scripts ask it for an archive path instead of spelling one out, so a column that an analysis renames
or drops fails here, with one line naming it, and not as a KeyError deep inside h5py:

    import columns
    columns.path("modes", "stability_margin_per_s")           # "results/modes/stability_margin_per_s"
    columns.path("open_loop", "height_m", series=True)        # "series/open_loop/height_m"
    columns.units("open_loop", "min_height_m")                # "m"
    columns.levels("landing", "outcome")                      # ["landed", "no_touchdown", ...]
    columns.time_axis("landing")                              # "series/landing/time_s"

An analysis's results and series are asked for apart (`series=True`): the two groups may hold the same
name.

The manifest is not a file of the repository: it is what the engine declares, asked of a gesweep
binary once per process (docs/architecture.md, "Describe once"). The first of these is read:
- GESWEEP_COLUMNS_MANIFEST: a manifest file (a test of a new analysis, say);
- GESWEEP_BINARY: the gesweep binary to ask;
- the gesweep that started this script (`gesweep report` runs scripts/report/report.py);
- build/gesweep of this repository.
Reference: schemas/archive.md ("The column manifest").
"""

import functools
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MANIFEST_ENV, BINARY_ENV = "GESWEEP_COLUMNS_MANIFEST", "GESWEEP_BINARY"
# The binary asked when nothing else says which (the build directory of README.md and scripts/test).
DEFAULT_BINARY = os.path.join(ROOT, "build", "gesweep")
# `gesweep columns --json` builds every analysis and lists its columns: well under a second.
COLUMNS_TIMEOUT_S = 120
# The manifest's own layout version this module reads (its `format_version`).
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


def launching_gesweep():
    """The gesweep binary that started this process (`gesweep report`), or None: the executable of
    the parent process when it is named gesweep (Linux /proc)."""
    try:
        executable = os.readlink(f"/proc/{os.getppid()}/exe")
    except OSError:
        return None
    return executable if os.path.basename(executable) == "gesweep" else None


def gesweep_binary():
    """The gesweep binary a script asks (the manifest, `gesweep check`): GESWEEP_BINARY, else the
    gesweep that started this script, else build/gesweep of this repository."""
    return os.environ.get(BINARY_ENV) or launching_gesweep() or DEFAULT_BINARY


def manifest_source():
    """(kind, path) of where the manifest comes from: ("file", FILE) or ("binary", GESWEEP)."""
    if os.environ.get(MANIFEST_ENV):
        return "file", os.environ[MANIFEST_ENV]
    return "binary", gesweep_binary()


def read_manifest(gesweep):
    """The manifest that the binary `gesweep` prints (`gesweep columns --json`), parsed; raises
    UnknownColumn, one line, when it cannot be run or fails."""
    try:
        out = subprocess.run([gesweep, "columns", "--json"], capture_output=True, text=True,
                             timeout=COLUMNS_TIMEOUT_S)
    except (OSError, subprocess.SubprocessError) as error:
        raise UnknownColumn(f"{gesweep}: cannot run `gesweep columns --json` for the column manifest ({error}); "
                            f"build it (cmake --build build) or set {BINARY_ENV} to a gesweep binary") from None
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or ["no message"])[-1]
        raise UnknownColumn(f"{gesweep}: `gesweep columns --json` failed (exit {out.returncode}): {last}")
    try:
        data = json.loads(out.stdout)
    except ValueError as error:
        raise UnknownColumn(f"{gesweep}: `gesweep columns --json` printed no JSON ({error})") from None
    return checked(data, gesweep)


def checked(data, where):
    """`data` when it is a manifest of the format this module reads."""
    if data.get("format") != "gesweep-columns" or data.get("format_version") != MANIFEST_FORMAT_VERSION:
        raise UnknownColumn(f"{where}: not a gesweep column manifest of format {MANIFEST_FORMAT_VERSION}")
    return data


@functools.cache
def manifest():
    """The manifest as parsed JSON (read once; see the module's docstring for where from)."""
    kind, path = manifest_source()
    if kind == "binary":
        return read_manifest(path)
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as error:
        raise UnknownColumn(f"{path}: cannot read the column manifest ({error}; {MANIFEST_ENV}); write it with "
                            f"`gesweep columns --json > FILE`") from None
    return checked(data, path)


def where():
    """What the messages name as the manifest: its file, or `GESWEEP columns --json`."""
    kind, path = manifest_source()
    return path if kind == "file" else f"`{path} columns --json`"


def analyses():
    """The names of every analysis, in archive column order."""
    return [a["name"] for a in manifest()["analyses"]]


def analysis(name):
    """The manifest entry of an analysis (name, description, columns, time_axes, ...)."""
    for entry in manifest()["analyses"]:
        if entry["name"] == name:
            return entry
    raise UnknownColumn(f"{where()}: no analysis '{name}' (analyses: {', '.join(analyses())})")


def column(analysis_name, name, series=False):
    """The manifest entry of one column: path, units, description, type, width, levels, ...; raises
    UnknownColumn naming the analysis, the column and the names it does have."""
    group = SERIES_GROUP if series else RESULTS_GROUP
    entry = analysis(analysis_name)
    for c in entry["columns"]:
        if c["group"] == group and c["name"] == name:
            return c
    known = [c["name"] for c in entry["columns"] if c["group"] == group]
    raise UnknownColumn(f"{where()}: analysis '{analysis_name}' has no {group} column '{name}' "
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
        raise UnknownColumn(f"{where()}: analysis '{analysis_name}' has {len(axes)} time axes, not one")
    return axes[0]["path"]


def design_path(parameter):
    """The archive path of a swept parameter ("design/<parameter>")."""
    for entry in manifest()["design"]:
        if entry["name"] == parameter:
            return entry["path"]
    raise UnknownColumn(f"{where()}: no design parameter '{parameter}'")


def runs_path(name):
    """The archive path of a bookkeeping dataset ("status" gives "runs/status")."""
    for entry in manifest()["runs"]:
        if entry["path"].split("/")[-1] == name:
            return entry["path"]
    raise UnknownColumn(f"{where()}: no runs dataset '{name}'")


def runs_paths():
    """The paths of every bookkeeping dataset (runs/index, runs/id, runs/status, runs/message)."""
    return tuple(entry["path"] for entry in manifest()["runs"])


def status_code(name):
    """The /runs/status code of the run status `name` ("pending", "ok", "failed"): the manifest's
    `run_status`, which the engine writes from RunStatus's names table (engine/sweep/runner.h)."""
    for entry in manifest()["run_status"]:
        if entry["name"] == name:
            return entry["code"]
    raise UnknownColumn(f"{where()}: no run status '{name}'")


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
