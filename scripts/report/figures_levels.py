"""The level maps (docs/report.md, "Level maps from the manifest"): one section per rated analysis of
the column manifest, its levels over height x speed with the stability map's overlays."""

import itertools
import os
import re
from dataclasses import dataclass

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D

import figures_common as common  # (first: it puts scripts/lib on the path)
import columns  # scripts/lib/columns.py
from figures_common import MAX_MAP_PANELS, MISSING_COLOUR, PAPER_SPEED_MPS, Figure
from figures_maps import height_speed_grid, map_axes, map_overlays

# Level maps: every rated analysis of the manifest (columns.ratings(): int8 columns whose levels are
# "level 1", "level 2", ..., a larger code worse; the one named "level" is the analysis's overall
# rating, the others rate its parts) is drawn over height x speed beside the stability map, with
# lines where each part loses a level. A new rated analysis appears without an edit here.
# The levels' colours, best to worst (MIL-F-8785C's Levels 1-3 and worse); more levels than these
# take evenly spaced colours of RdYlGn_r.
LEVEL_COLOURS = ("#1a9850", "#fee08b", "#f46d43", "#7f0000")
# The parts' lines, in the order the parts are drawn (the last-declared part first: the phugoid, then
# the short period, of flying_qualities): style and width.
# (Dash-dot before dotted: the last table row's line is dotted.)
LEVEL_PART_STYLES = (("-", 2.2), ((0, (4, 2)), 1.6), ((0, (6, 2, 1, 2)), 1.6), ((0, (1, 1.5)), 1.6))
# Wording of the figures of the analyses that have their own (section title, what a part is, the
# caption's opening with {grid} for "N speeds × M heights (R runs of FILE)"); any other rated
# analysis is described from its manifest entry.
LEVEL_MAP_WORDING = {
    "flying_qualities": ("Flying qualities (MIL-F-8785C, Category C)", "mode",
                         "Levels of the bare airframe's short period and phugoid over {grid}, rated against "
                         "MIL-F-8785C for Category C (approach and landing) as docs/model.md §11 states it; the "
                         "ground-effect height mode has no requirement."),
}
# The study that writes each analysis's levels for the report, named when no archive holds them.
LEVEL_MAP_STUDIES = {"flying_qualities": "studies/paper/flying_qualities.toml"}
# A rating's description: "<standard> level of <subject>: ..." or "<standard> level of <part> (<paragraph>)".
_RATING_DESCRIPTION = re.compile(r"^(?P<standard>.*?)\s*\blevel of (?P<subject>[^:(]+?)\s*(?::|\(|$)")
_PARAGRAPH = re.compile(r"\((\d+(?:\.\d+)+)\)")


@dataclass
class RatedAnalysis:
    """What the level map of one analysis reads: from columns.ratings()."""
    name: str              # the analysis ("flying_qualities")
    description: str       # its description in the manifest
    overall: dict | None   # its overall rating column (manifest entry), if it has one
    parts: list            # the ratings of its parts, in declaration order

    @property
    def label(self):
        return self.name.replace("_", " ")

    def part_label(self, part):
        return part["name"].removesuffix("_level").replace("_", " ")

    def section_title(self):
        wording = LEVEL_MAP_WORDING.get(self.name)
        return wording[0] if wording else f"{self.label[:1].upper()}{self.label[1:]} (levels)"

    def paths(self):
        return [c["path"] for c in ([self.overall] if self.overall else []) + self.parts]


def rated_analyses():
    """Every analysis of the manifest with rated columns, as RatedAnalysis."""
    return [RatedAnalysis(entry["name"], entry["description"], overall, parts)
            for entry, overall, parts in columns.ratings()]


def draw(archives, outdir, rated=None):
    """One figure per group of an archive's runs over height x speed for each rated analysis
    (`rated`: one RatedAnalysis, or all of them): the overall level (or the worst of the parts') and,
    drawn over it, where each part loses each level."""
    figures = []
    for analysis in [rated] if rated is not None else rated_analyses():
        for archive in archives:
            if not (all(archive.has(p) for p in analysis.paths()) and "height_m" in archive.design_names
                    and "speed_mps" in archive.design_names):
                continue
            for number, (key, rows) in enumerate(archive.groups(("height_m", "speed_mps"))[:MAX_MAP_PANELS]):
                figure = _level_map(archive, analysis, key, rows[archive.ok[rows]], outdir, number)
                if figure is not None:
                    figures.append(figure)
    return figures


def _level_colours(count):
    if count <= len(LEVEL_COLOURS):
        return matplotlib.colors.ListedColormap(LEVEL_COLOURS[:count])
    return matplotlib.colors.ListedColormap(plt.get_cmap("RdYlGn_r")(np.linspace(0, 1, count)))


def _level_map_title(analysis):
    """The panel's title: "<subject>'s level: the worse of <part> (<paragraph>) and <part> (...)"."""
    parts = []
    for part in analysis.parts:
        paragraph = _PARAGRAPH.search(part["description"])
        parts.append(analysis.part_label(part) + (f" ({paragraph.group(1)})" if paragraph else ""))
    match = _RATING_DESCRIPTION.match(analysis.overall["description"]) if analysis.overall else None
    subject = match.group("subject") if match else "the"
    owner = f"{subject}'s level" if match else "the level"
    worst = "the worse of" if len(parts) == 2 else "the worst of"
    return f"{owner}: {worst} " + (" and ".join(parts) if len(parts) <= 2 else ", ".join(parts))


def _level_map_standard(analysis):
    """The standard the ratings name ("MIL-F-8785C Category C"), or ""."""
    for column in ([analysis.overall] if analysis.overall else []) + analysis.parts:
        match = _RATING_DESCRIPTION.match(column["description"])
        if match and match.group("standard"):
            return match.group("standard")
    return ""


def _level_map(archive, analysis, key, rows, outdir, number):
    heights, speeds = np.unique(archive.param("height_m")[rows]), np.unique(archive.param("speed_mps")[rows])
    if len(heights) < 2 or len(speeds) < 2:
        return None
    first = analysis.overall or analysis.parts[0]
    names = archive.levels(first["path"]) or first["levels"]
    grids = {part["name"]: height_speed_grid(archive, rows, heights, speeds, part["path"]) for part in analysis.parts}
    if analysis.overall is not None:
        level = height_speed_grid(archive, rows, heights, speeds, analysis.overall["path"])
    else:  # the worst of the parts (a larger code is worse); NaN where any part has none
        level = np.max(np.stack(list(grids.values())), axis=0)
    colours = _level_colours(len(names))
    colours.set_bad(MISSING_COLOUR)
    norm = matplotlib.colors.BoundaryNorm(np.arange(len(names) + 1) - 0.5, len(names))
    fig, (ax, legend_axis) = plt.subplots(2, 1, figsize=(8.8, 6.6), layout="constrained",
                                          gridspec_kw={"height_ratios": [1, 0.2]})
    mesh = ax.pcolormesh(speeds, heights, np.ma.masked_invalid(level), cmap=colours, norm=norm, shading="nearest",
                         rasterized=True)
    handles = {}
    lost = []
    wording = LEVEL_MAP_WORDING.get(analysis.name)
    for part, (style, width) in zip(analysis.parts[::-1], itertools.cycle(LEVEL_PART_STYLES)):
        label = analysis.part_label(part)
        grid = grids[part["name"]]
        present = [code for code in range(len(names) - 1) if np.nanmin(grid) <= code < np.nanmax(grid)]
        if present:
            ax.contour(speeds, heights, grid, levels=[code + 0.5 for code in present], colors="k",
                       linestyles=[style], linewidths=width)
            handles[label] = Line2D([], [], color="k", ls=style, lw=width,
                                    label=f"{label}: where it loses a level (between the colours)")
        lost.append(_levels_lost_text(archive, rows, part["path"], label, names))
    # A grid with no sign change: the overlays without a zero contour.
    for handle in map_overlays(ax, archive, key, heights, speeds, np.zeros_like(level), ""):
        handles.setdefault(handle.get_label(), handle)
    map_axes(ax, archive, heights, speeds)
    ax.set_title(_level_map_title(analysis))
    bar = fig.colorbar(mesh, ax=ax, pad=0.02, aspect=30, ticks=range(len(names)))
    bar.ax.set_yticklabels(names)
    common.legend_row(fig, legend_axis, list(handles.values()), ncols=2)
    suffix = f" ({archive.key_text(key)})" if key else ""
    standard = _level_map_standard(analysis)
    fig.suptitle(f"{archive.aircraft.name or 'aircraft'}: {standard + ' ' if standard else ''}{analysis.label}{suffix}")
    name = common.save(fig, outdir, f"{analysis.name}_{common.slug(archive.study_name)}_{number}.png")
    grid_text = (f"{len(speeds)} speeds × {len(heights)} heights ({len(rows)} runs of "
                 f"{os.path.basename(archive.path)})")
    if wording:
        opening = wording[2].format(grid=grid_text) + f" Black lines mark where a {wording[1]} changes level. "
    else:
        labels = [analysis.part_label(p) for p in analysis.parts]
        parts = labels[0] if len(labels) == 1 else ", ".join(labels[:-1]) + " and " + labels[-1]
        opening = (f"Levels of {parts} ({analysis.description}) over {grid_text}, from "
                   f"the {analysis.name} columns of the archive. Black lines mark where each changes level. ")
    caption = opening + " ".join(t for t in lost if t)
    title = f"{analysis.label[:1].upper()}{analysis.label[1:]} ({archive.study_name}){suffix}"
    return Figure(name, title, caption)


def _levels_lost_text(archive, rows, path, part, names):
    """Where `part` loses each level along height at the paper's speed (or the speed nearest to it)."""
    speed = archive.param("speed_mps")[rows]
    nearest = speed[np.argmin(np.abs(speed - PAPER_SPEED_MPS))]
    along = rows[speed == nearest]
    along = along[np.argsort(archive.param("height_m")[along])]
    height = archive.param("height_m")[along]
    code = archive.column(path)[along]
    if not np.all(np.isfinite(code)):
        return ""
    # From the top down: each change of level, between the two grid heights that bracket it.
    changes = np.nonzero(np.diff(code) != 0)[0][::-1]
    if len(changes) == 0:
        return f"At u0 = {nearest:g} m/s the {part} is {names[int(code[0])]} at every height of the grid."
    parts = [f"{names[int(code[-1])]} from {height[-1]:.4g} m down to {height[changes[0] + 1]:.4g} m"]
    for i in changes:
        parts.append(f"{names[int(code[i])]} from {height[i]:.4g} m")
    return f"At u0 = {nearest:g} m/s the {part} is " + ", ".join(parts) + "."

