"""The report's figures (docs/report.md, "gesweep report"). Each function draws a figure only when the
archives hold its data, and returns a list of Figure records (file name, title, caption)."""

import itertools
import math
import os
import re
import sys
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, Normalize, SymLogNorm  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.text import Text  # noqa: E402

_LIB = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "lib")
if _LIB not in sys.path:
    sys.path.insert(0, _LIB)
import columns  # noqa: E402  (scripts/lib/columns.py: archive paths from `gesweep columns --json`)

# The columns the figures read (the column manifest; a renamed column fails here, at import).
SIGMA = columns.path("modes", "stability_margin_per_s")
SIGMA_UNITS = columns.units("modes", "stability_margin_per_s")
PHUGOID_RE = columns.path("modes", "phugoid/eigenvalue_re_per_s")
HEIGHT_RE = columns.path("modes", "height/eigenvalue_re_per_s")
MODE_EIGENVALUES = {  # (Re, Im) of each mode
    "short_period": (columns.path("modes", "short_period/eigenvalue_re_per_s"),
                     columns.path("modes", "short_period/eigenvalue_im_per_s")),
    "phugoid": (PHUGOID_RE, columns.path("modes", "phugoid/eigenvalue_im_per_s")),
    "height": (HEIGHT_RE, columns.path("modes", "height/eigenvalue_im_per_s")),
}
OPEN_LOOP_HEIGHT = columns.path("open_loop", "height_m", series=True)
OPEN_LOOP_TIME = columns.time_axis("open_loop")
LANDING_TIME = columns.time_axis("landing")
LANDING_SERIES = {
    "height_m": columns.path("landing", "height_m", series=True),
    "distance_past_transmitter_m": columns.path("landing", "distance_past_transmitter_m", series=True),
    "elevator_rad": columns.path("landing", "elevator_rad", series=True),
    "pitch_rate_radps": columns.path("landing", "pitch_rate_radps", series=True),
}


# The paper's open-loop speed (Section IV): the root locus prefers the runs nearest to it.
PAPER_SPEED_MPS = 32.0208
# Runs within this of the paper's speed are as good as at it for the root locus; among them, the
# densest in height wins.
LOCUS_SPEED_WINDOW_MPS = 0.5
# Runs of two archives are at the same speed when within this (studies store 32.0208 exactly).
SAME_SPEED_MPS = 1e-6
# A group at exactly the paper's speed is preferred for the root locus when it has at least this many
# heights (fewer draw a polygon, not a locus: the 11 Table A2 heights are drawn as circles over it).
LOCUS_DENSE_HEIGHTS = 50
# Distances (points) from a marked height at which its label is tried, nearest first.
LOCUS_LABEL_RADII_PT = (14, 26, 42, 60, 85, 115)
# A step of the short-period locus this many times its median step is "fast" and explained in the caption.
LOCUS_FAST_STEP_RATIO = 8.0
# The derivatives that set the short-period root (pitch stiffness and damping, lift slope).
SHORT_PERIOD_DERIVATIVES = ("CMalphadot", "CMq", "CMalpha", "CLalpha")
DERIVATIVE_NAMES = {"CMalphadot": "CMα̇", "CMq": "CMq", "CMalpha": "CMα", "CLalpha": "CLα"}
DERIVATIVE_MATHTEXT = {"CMalphadot": r"$C_{M\dot{\alpha}}$", "CMq": r"$C_{Mq}$", "CMalpha": r"$C_{M\alpha}$",
                       "CLalpha": r"$C_{L\alpha}$"}
DPI = 110
# Heights spaced by a constant ratio to this relative tolerance are drawn on a log axis.
GEOMETRIC_SPACING_TOLERANCE = 1e-6
MAX_MAP_PANELS = 4
# The stability map's colour scale is linear within ±this and logarithmic beyond (1/s): a phugoid
# doubling in about 12 min is still visibly red.
SIGMA_LINEAR_PER_S = 1e-3
MISSING_COLOUR = "#b0b0b0"
MAX_OPEN_LOOP_LINES = 12
# The open-loop lines take tab10's colours, its brown too: the wheel-contact line there is black.
WHEEL_COLOUR_OPEN_LOOP = "k"
# Names at the ends of the open-loop lines are at least this fraction of the height axis apart.
OPEN_LOOP_END_LABEL_GAP = 0.045
MAX_LANDING_LINES = 6

plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 8.5,
                     "figure.dpi": DPI, "savefig.dpi": DPI})


@dataclass
class Figure:
    file: str
    title: str
    caption: str


def _save(fig, outdir, name):
    # No bbox_inches="tight": it draws the figure twice; the figures use constrained layout instead.
    fig.savefig(os.path.join(outdir, name))
    plt.close(fig)
    return name


def _slug(text):
    return "".join(c if c.isalnum() else "_" for c in text).strip("_").lower()


def _geometric(values):
    values = np.asarray(values)
    if len(values) < 3 or np.any(values <= 0):
        return False
    ratios = values[1:] / values[:-1]
    return float(np.std(ratios) / np.mean(ratios)) < GEOMETRIC_SPACING_TOLERANCE


def _span_axis(ax, wingspan_m):
    """A secondary height axis in H/b on the right."""
    if not (wingspan_m > 0):
        return
    secondary = ax.secondary_yaxis("right", functions=(lambda h: h / wingspan_m, lambda r: r * wingspan_m))
    secondary.set_ylabel("H/b (height over wingspan)")
    if ax.get_yscale() != "log":
        return  # the default locator spaces a linear axis well
    low, high = (h / wingspan_m for h in ax.get_ylim())
    ticks = [t for t in (0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1, 1.5, 2, 2.5, 3, 4, 5, 10, 20, 50, 100)
             if low <= t <= high]
    if len(ticks) >= 2:
        secondary.set_yticks(ticks)
        secondary.set_yticklabels([f"{t:g}" for t in ticks])
        secondary.minorticks_off()


def _h_derivatives_label(archive, key):
    parts = []
    for name, value in key.items():
        if name == "h_derivatives":
            parts.append("with h-derivatives" if value == 1 else "without h-derivatives")
        else:
            parts.append(f"{name} = {archive.level_name(name, value)}")
    return ", ".join(parts)


def stability_maps(archives, outdir):
    """One stability-map figure per group of an archive's runs over height x speed (up to
    MAX_MAP_PANELS groups: one per value of any other swept parameter)."""
    figures = []
    for archive in archives:
        if not (archive.has(SIGMA) and "height_m" in archive.design_names
                and "speed_mps" in archive.design_names):
            continue
        for number, (key, rows) in enumerate(archive.groups(("height_m", "speed_mps"))[:MAX_MAP_PANELS]):
            figure = _stability_map(archive, key, rows[archive.ok[rows]], outdir, number)
            if figure is not None:
                figures.append(figure)
    return figures


def _height_speed_grid(archive, rows, heights, speeds, path):
    """A per-run column on the heights x speeds grid of `rows` (NaN where no ok run)."""
    grid = np.full((len(heights), len(speeds)), np.nan)
    height, speed = archive.param("height_m")[rows], archive.param("speed_mps")[rows]
    grid[np.searchsorted(heights, height), np.searchsorted(speeds, speed)] = archive.column(path)[rows]
    return grid


def _stability_map(archive, key, rows, outdir, number):
    """The stability map of one group of runs: σ over height x speed and, when the archive has it, the
    phugoid's own real part on the same colour scale; every line of the map is drawn by
    _map_overlays."""
    heights, speeds = np.unique(archive.param("height_m")[rows]), np.unique(archive.param("speed_mps")[rows])
    if len(heights) < 2 or len(speeds) < 2:
        return None
    sigma = _height_speed_grid(archive, rows, heights, speeds, SIGMA)
    panels = [(sigma, "σ = 0 on the grid", "stability margin σ: the largest Re λ, the exactly neutral height root left out")]
    phugoid = None
    if archive.has(PHUGOID_RE):
        phugoid = _height_speed_grid(archive, rows, heights, speeds, PHUGOID_RE)
        zero = "σ = 0 (upper panel), Re λ = 0 (lower panel) on the grid"
        panels = [(sigma, zero, panels[0][2]), (phugoid, zero, "the phugoid's own margin: Re λ of the phugoid")]
    extent = max(max(np.nanmax(np.abs(grid)) for grid, _, _ in panels), 1e-12)
    # Symmetric about 0 (white), logarithmic beyond SIGMA_LINEAR_PER_S so that the small margins near
    # the boundary are as visible as the large ones near the ground; one scale for both panels.
    norm = SymLogNorm(linthresh=min(SIGMA_LINEAR_PER_S, extent / 10), linscale=0.6, vmin=-extent, vmax=extent,
                      base=10)
    colours = plt.get_cmap("RdBu_r").copy()
    colours.set_bad(MISSING_COLOUR)  # a run not complete (or failed): not white, which is σ = 0
    fig, axes = plt.subplots(len(panels) + 1, 1, figsize=(8.8, 1.4 + 4.3 * len(panels)), layout="constrained",
                             gridspec_kw={"height_ratios": [1] * len(panels) + [0.2]})
    legend_axis = axes[-1]
    mesh, handles = None, {}
    for ax, (grid, zero_label, title) in zip(axes[:-1], panels):
        mesh = ax.pcolormesh(speeds, heights, np.ma.masked_invalid(grid), cmap=colours, norm=norm,
                             shading="nearest", rasterized=True)
        for handle in _map_overlays(ax, archive, key, heights, speeds, grid, zero_label):
            handles.setdefault(handle.get_label(), handle)
        _map_axes(ax, archive, heights, speeds)
        ax.set_title(title)
    for ax in axes[:-2]:
        ax.set_xlabel("")
    bar = fig.colorbar(mesh, ax=list(axes[:-1]), pad=0.02, aspect=35)
    bar.set_label(f"σ, Re λ ({SIGMA_UNITS}): red unstable (> 0), blue stable (< 0)")
    legend_axis.axis("off")
    legend_axis.legend(handles=list(handles.values()), loc="center", ncols=2, frameon=False)
    suffix = f" ({_h_derivatives_label(archive, key)})" if key else ""
    fig.suptitle(f"{archive.aircraft.name or 'aircraft'}: stability over height and speed{suffix}")
    name = _save(fig, outdir, f"stability_map_{_slug(archive.study_name)}_{number}.png")
    return Figure(name, f"Stability map ({archive.study_name}){suffix}",
                  _map_caption(archive, rows, heights, speeds, sigma, phugoid))


def _map_overlays(ax, archive, key, heights, speeds, grid, zero_label):
    """The lines over one panel of the stability map; returns their legend handles. Everything drawn
    over the map is here: the zero contour of the panel's quantity, the refined boundary H*, H/b = 0.5,
    the wheel-contact height and the last table row."""
    handles = []
    b = archive.aircraft.wingspan_m
    if np.nanmin(grid) < 0 < np.nanmax(grid):
        ax.contour(speeds, heights, grid, levels=[0.0], colors="k", linewidths=2.4)
        handles.append(Line2D([], [], color="k", lw=2.4, label=zero_label))
    boundary = archive.boundary()
    if boundary is not None and "speed_mps" in boundary["keys"]:
        select = np.ones(len(boundary["speed_mps"]), dtype=bool)
        for name, value in key.items():
            if name in boundary:
                select &= boundary[name] == value
        found = select & np.isfinite(boundary["height_m"])
        if np.any(found):
            ax.plot(boundary["speed_mps"][found], boundary["height_m"][found], color="#ffd000", lw=0.9,
                    marker="o", ms=3, mec="k", mew=0.4)
            handles.append(Line2D([], [], color="#ffd000", lw=0.9, marker="o", ms=3.5, mec="k", mew=0.4,
                                  label="H* refined on the continuous model (/analysis/boundary)"))
    # The curve H*(u0) traced by continuation (gesweep boundary --archive, issue 16), when the map's
    # only other axis is speed.
    if "analysis/boundary_curve" in archive.file and len(key) == 0:
        traced = archive.file["analysis/boundary_curve"]
        branches = traced["branch"][...]
        for branch in np.unique(branches):
            on = branches == branch
            ax.plot(traced["speed_mps"][...][on], traced["height_m"][...][on], color="#ff00c8", lw=1.4)
        if len(branches):
            handles.append(Line2D([], [], color="#ff00c8", lw=1.4,
                                  label="H*(u0) traced by continuation (/analysis/boundary_curve)"))
    if b > 0:
        ax.axhline(0.5 * b, color="#00a000", ls="--", lw=1.4)
        handles.append(Line2D([], [], color="#00a000", ls="--", lw=1.4,
                              label=f"H/b = 0.5 ({0.5 * b:.5g} m): the paper's boundary"))
    wheel = archive.aircraft.wheel_contact_height_m
    if wheel > 0 and heights[0] <= wheel <= heights[-1]:
        ax.axhline(wheel, color="saddlebrown", lw=1.2)
        handles.append(Line2D([], [], color="saddlebrown", lw=1.2, label=f"wheel contact ({wheel:.3g} m)"))
    last_row = _last_table_row_m(archive)
    if heights[0] < last_row < heights[-1]:
        ax.axhline(last_row, color="0.25", ls=":", lw=1.2)
        handles.append(Line2D([], [], color="0.25", ls=":", lw=1.2,
                              label=f"last table row ({last_row:.5g} m): free-flight coefficients above"))
    return handles


def _map_axes(ax, archive, heights, speeds):
    if _geometric(heights):
        ax.set_yscale("log")
        ticks = [t for t in (0.8, 1, 1.5, 2, 3, 4, 5, 7, 10, 14, 20, 30, 50) if heights[0] <= t <= heights[-1]]
        ax.set_yticks(ticks)
        ax.set_yticklabels([f"{t:g}" for t in ticks])
        ax.minorticks_off()
    ax.set_xlim(speeds[0], speeds[-1])
    ax.set_ylim(heights[0], heights[-1])
    _span_axis(ax, archive.aircraft.wingspan_m)
    ax.set_xlabel("reference speed u0 (m/s)")
    ax.set_ylabel("height H of the mean chord (m)")


def _last_table_row_m(archive):
    rows = archive.aircraft.table_heights_m
    return float(rows[-1]) if rows else math.nan


def _map_caption(archive, rows, heights, speeds, sigma, phugoid):
    text = (f"Eigen-analysis of Eq. (1) over {len(speeds)} speeds × {len(heights)} heights ({len(rows)} runs of "
            f"{os.path.basename(archive.path)}). Colours are centred on 0 (white), linear within "
            f"±{SIGMA_LINEAR_PER_S:g} 1/s and logarithmic beyond, one scale for both panels; grey cells have no "
            f"complete ok run. The yellow curve, where present, is the boundary H* refined on the continuous "
            f"model by gesweep boundary --archive.")
    if phugoid is None:
        return text
    height_root = (_height_speed_grid(archive, rows, heights, speeds, HEIGHT_RE)
                   if archive.has(HEIGHT_RE) else None)
    stable = np.isfinite(sigma) & (sigma < 0)
    from_height = stable & (sigma == height_root) if height_root is not None else np.zeros_like(stable)
    if np.any(from_height):
        values = sigma[from_height]
        text += (f" σ is the largest real part of the three modes: in {100 * from_height.sum() / stable.sum():.0f} % "
                 f"of the stable cells it is the height root (median {np.median(values):.2g} 1/s; within "
                 f"±{SIGMA_LINEAR_PER_S:g} 1/s, nearly white, in "
                 f"{100 * np.mean(np.abs(values) < SIGMA_LINEAR_PER_S):.0f} % of them), not the phugoid, so the upper "
                 f"panel does not show how damped the phugoid is; the lower panel does.")
    last_row = _last_table_row_m(archive)
    above, below = heights > last_row, heights < last_row
    if np.any(above) and np.any(below):
        i, j = np.nonzero(below)[0][-1], np.nonzero(above)[0][0]
        # The band is there when σ just below the last row is mostly the height root.
        if np.mean(from_height[i]) > 0.5:
            text += (f" Above the last table row ({last_row:.5g} m) the coefficients are the free-flight row and no "
                     f"longer change with height, so the height root is exactly neutral and is left out of σ "
                     f"(docs/model.md §6): σ jumps from the height root (median {np.nanmedian(sigma[i]):.2g} 1/s at "
                     f"{heights[i]:.4g} m) to the phugoid (median {np.nanmedian(sigma[j]):.2g} 1/s at "
                     f"{heights[j]:.4g} m). The dark band at the top of the upper panel is that change of mode, not "
                     f"a change of the airplane's stability; the phugoid panel has no band.")
    return text


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


def level_maps(archives, outdir, rated=None):
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
    grids = {part["name"]: _height_speed_grid(archive, rows, heights, speeds, part["path"]) for part in analysis.parts}
    if analysis.overall is not None:
        level = _height_speed_grid(archive, rows, heights, speeds, analysis.overall["path"])
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
    for handle in _map_overlays(ax, archive, key, heights, speeds, np.zeros_like(level), ""):
        handles.setdefault(handle.get_label(), handle)
    _map_axes(ax, archive, heights, speeds)
    ax.set_title(_level_map_title(analysis))
    bar = fig.colorbar(mesh, ax=ax, pad=0.02, aspect=30, ticks=range(len(names)))
    bar.ax.set_yticklabels(names)
    legend_axis.axis("off")
    legend_axis.legend(handles=list(handles.values()), loc="center", ncols=2, frameon=False)
    suffix = f" ({_h_derivatives_label(archive, key)})" if key else ""
    standard = _level_map_standard(analysis)
    fig.suptitle(f"{archive.aircraft.name or 'aircraft'}: {standard + ' ' if standard else ''}{analysis.label}{suffix}")
    name = _save(fig, outdir, f"{analysis.name}_{_slug(archive.study_name)}_{number}.png")
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


def _locus_groups(archives):
    """Every group of runs along height with the modes: (archive, key, rows sorted by height, speed,
    h-derivatives on)."""
    groups = []
    for archive in archives:
        if not (archive.has(MODE_EIGENVALUES["short_period"][0]) and "height_m" in archive.design_names):
            continue
        height = archive.param("height_m")
        speed = archive.param("speed_mps")
        h_derivatives = archive.param("h_derivatives")
        for key, rows in archive.groups(("height_m",)):
            rows = rows[archive.ok[rows]]
            if len(rows) == 0 or speed is None:
                continue
            on = h_derivatives is None or h_derivatives[rows[0]] == 1
            groups.append((archive, key, rows[np.argsort(height[rows])], float(speed[rows[0]]), on))
    return groups


def _locus_source(groups):
    """The group for the root locus: h-derivatives on; at exactly the paper's speed with at least
    LOCUS_DENSE_HEIGHTS heights if any group is, else within LOCUS_SPEED_WINDOW_MPS of it; then the most
    heights, then the nearest speed."""
    best = None
    for group in groups:
        archive, key, rows, speed, on = group
        distinct = len(np.unique(archive.param("height_m")[rows]))
        if distinct < 5:
            continue
        at_paper_speed = abs(speed - PAPER_SPEED_MPS) < SAME_SPEED_MPS and distinct >= LOCUS_DENSE_HEIGHTS
        score = (0 if on else 1, 0 if at_paper_speed else 1, abs(speed - PAPER_SPEED_MPS) > LOCUS_SPEED_WINDOW_MPS,
                 -distinct, abs(speed - PAPER_SPEED_MPS))
        if best is None or score < best[0]:
            best = (score, group)
    return None if best is None else best[1]


def _label_candidates():
    """Offsets (points) tried for a label, nearest first."""
    out = []
    for radius in LOCUS_LABEL_RADII_PT:
        for degrees in (45, 0, -45, 90, -90, 135, 180, -135):
            angle = math.radians(degrees)
            out.append((radius * math.cos(angle), radius * math.sin(angle)))
    return out


def _place_labels(fig, ax, points, anchors, texts, taken):
    """Writes `texts` beside the points `anchors` (data coordinates) of a panel whose curve is `points`
    (N x 2), each at the first offset where its text overlaps no label already placed (`taken`, display
    boxes), covers the fewest points of the curve and stays inside the axes. Needs the layout done
    (the figure's layout engine executed); the labels are left out of the layout after it."""
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    curve = ax.transData.transform(points)
    for anchor, text in zip(anchors, texts):
        best = None
        for dx, dy in _label_candidates():
            label = ax.annotate(text, anchor, xytext=(dx, dy), textcoords="offset points", fontsize=8,
                                ha="left" if dx > 1 else ("right" if dx < -1 else "center"),
                                va="bottom" if dy > 1 else ("top" if dy < -1 else "center"),
                                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.85),
                                arrowprops=dict(arrowstyle="-", color="0.4", lw=0.6, shrinkA=0, shrinkB=2))
            label.update_positions(renderer)
            box = Text.get_window_extent(label, renderer).expanded(1.08, 1.15)
            inside = (box.x0 >= frame.x0 and box.x1 <= frame.x1 and box.y0 >= frame.y0 and box.y1 <= frame.y1)
            covered = int(np.count_nonzero((curve[:, 0] >= box.x0) & (curve[:, 0] <= box.x1) & (curve[:, 1] >= box.y0)
                                           & (curve[:, 1] <= box.y1)))
            cost = (sum(box.overlaps(other) for other in taken), 0 if inside else 1, covered)
            if best is None or cost < best[0]:
                if best is not None:
                    best[1].remove()
                best = (cost, label, box)
            else:
                label.remove()
            if cost == (0, 0, 0):
                break
        best[1].set_in_layout(False)
        taken.append(best[2])


def _fast_segment(archive, height, re, im):
    """Where the short-period root moves farthest per grid step, if it stands out (a step more than
    LOCUS_FAST_STEP_RATIO times the median): (lower row, upper row, coefficient, value below, value
    above, index of the step) of the aircraft's table interval that holds it and of its short-period
    derivative that changes most there relative to its range; else None."""
    rows = archive.aircraft.table_heights_m
    if len(height) < 3 or len(rows) < 2:
        return None
    step = np.hypot(np.diff(re), np.diff(im))
    k = int(np.argmax(step))
    if not step[k] > LOCUS_FAST_STEP_RATIO * np.median(step):
        return None
    middle = 0.5 * (height[k] + height[k + 1])
    j = int(np.searchsorted(rows, middle))
    if not 0 < j < len(rows):
        return None
    best = None
    for name in SHORT_PERIOD_DERIVATIVES:
        values = archive.aircraft.table.get(name)
        if not values:
            continue
        scale = max(abs(v) for v in values)
        change = abs(values[j] - values[j - 1]) / scale if scale > 0 else 0.0
        if best is None or change > best[0]:
            best = (change, name, values[j - 1], values[j])
    if best is None:
        return None
    return rows[j - 1], rows[j], best[1], best[2], best[3], k


def root_locus(archives, outdir):
    groups = _locus_groups(archives)
    source = _locus_source(groups)
    if source is None:
        return []
    archive, key, rows, speed, on = source
    height = archive.param("height_m")[rows]
    modes = {m: (archive.column(re)[rows], archive.column(im)[rows]) for m, (re, im) in MODE_EIGENVALUES.items()}
    at_paper_speed = abs(speed - PAPER_SPEED_MPS) < SAME_SPEED_MPS
    # The paper's own points: runs at exactly its speed at a few heights (the Table A2 study), if any.
    table_points = None
    for other in groups:
        if (other is not source and other[4] == on and abs(other[3] - speed) < SAME_SPEED_MPS and at_paper_speed
                and len(other[2]) <= 30):
            a, _, r, _, _ = other
            table_points = (a.param("height_m")[r], {m: (a.column(re)[r], a.column(im)[r])
                                                     for m, (re, im) in MODE_EIGENVALUES.items()}, a.study_name)
            break
    b = archive.aircraft.wingspan_m
    norm = LogNorm(height.min(), height.max()) if height.min() > 0 else Normalize(height.min(), height.max())
    fig = plt.figure(figsize=(14, 5.6), layout="constrained")
    grid = fig.add_gridspec(2, 3, width_ratios=[1, 1, 0.9], height_ratios=[1, 0.07])
    axes = [fig.add_subplot(grid[0, i]) for i in range(3)]
    legend_axis = fig.add_subplot(grid[1, :])
    # Heights named along the locus: the lowest, H/b = 0.5, H/b = 1 and the highest.
    marks = sorted({0, len(height) - 1} | {int(np.argmin(np.abs(height - r * b))) for r in (0.5, 1.0)
                                            if b > 0 and height.min() <= r * b <= height.max()})
    scatter = None
    for ax, mode, title in ((axes[0], "short_period", "short-period mode"), (axes[1], "phugoid", "phugoid mode")):
        re, im = modes[mode]
        ax.plot(re, im, color="0.55", lw=0.8, zorder=1)
        scatter = ax.scatter(re, im, c=height, cmap="viridis", norm=norm, s=16, zorder=2, edgecolors="none")
        ax.scatter(re[-1:], im[-1:], marker="*", s=140, color="k", zorder=3)
        ax.scatter(re[:1], im[:1], marker="X", s=80, color="#c00000", zorder=3)
        if table_points is not None:
            tre, tim = table_points[1][mode]
            ax.scatter(tre, tim, marker="o", s=46, facecolors="none", edgecolors="k", lw=1.0, zorder=4)
        ax.margins(0.12)
        low, high = ax.get_xlim()
        if low < 0 < high:
            ax.axvline(0.0, color="#c00000", lw=0.9, ls="--")
        ax.set_xlabel("Re λ (1/s)")
        ax.set_ylabel("Im λ (1/s)")
        ax.set_title(f"{title} (upper half-plane)")
        ax.grid(alpha=0.3)
    re = modes["height"][0]
    axes[2].plot(height, re, color="0.55", lw=0.8)
    axes[2].scatter(height, re, c=height, cmap="viridis", norm=norm, s=14, edgecolors="none")
    if table_points is not None:
        axes[2].scatter(table_points[0], table_points[1]["height"][0], marker="o", s=46, facecolors="none",
                        edgecolors="k", lw=1.0, zorder=4)
    axes[2].axhline(0.0, color="#c00000", lw=0.9, ls="--")
    if b > 0:
        axes[2].axvline(0.5 * b, color="#00a000", lw=1.0, ls="--")
    axes[2].set_xscale("log")
    axes[2].set_xlabel("height H (m)")
    axes[2].set_ylabel("λ of the height mode (real, 1/s)")
    axes[2].set_title("height (subsidence) mode")
    axes[2].grid(alpha=0.3)
    handles = [Line2D([], [], marker="*", ls="", color="k", ms=11, label=f"highest: {height[-1]:.3g} m"),
               Line2D([], [], marker="X", ls="", color="#c00000", ms=8, label=f"lowest: {height[0]:.3g} m"),
               Line2D([], [], color="#c00000", ls="--", label="Re λ = 0")]
    if b > 0:
        handles.append(Line2D([], [], color="#00a000", ls="--", label="H/b = 0.5"))
    if table_points is not None:
        handles.append(Line2D([], [], marker="o", ls="", mfc="none", mec="k",
                              label=f"Table A2 heights ({table_points[2]})"))
    legend_axis.axis("off")
    legend_axis.legend(handles=handles, loc="center", ncols=len(handles), frameon=False)
    bar = fig.colorbar(scatter, ax=axes, pad=0.01, aspect=30)
    bar.set_label("height H (m)")
    others = {k: v for k, v in key.items() if k != "speed_mps"}
    if at_paper_speed:
        condition = f"u0 = {speed:.6g} m/s, the paper's speed, "
    else:
        condition = (f"u0 = {speed:.6g} m/s, the speed of {archive.study_name} nearest the paper's "
                     f"{PAPER_SPEED_MPS} m/s, ")
    condition += ("with" if on else "without") + " h-derivatives"
    if any(k != "h_derivatives" for k in others):
        condition += ", " + archive.key_text({k: v for k, v in others.items() if k != "h_derivatives"})
    fig.suptitle(f"Root locus as height falls from {height[-1]:.3g} m to {height[0]:.3g} m ({condition})")
    # Labels last, where they cover nothing: on the laid-out figure (the layout alone, not a full draw).
    fig.get_layout_engine().execute(fig)
    taken = []
    texts = [f"{height[i]:.3g} m" + (f" (H/b {height[i] / b:.2f})" if b > 0 else "") for i in marks]
    fast = _fast_segment(archive, height, *modes["short_period"])
    for ax, mode in ((axes[0], "short_period"), (axes[1], "phugoid")):
        points = np.column_stack(modes[mode])
        anchors, labels = [points[i] for i in marks], list(texts)
        if fast is not None and mode == "short_period":
            low_row, high_row, coefficient, below, above, _ = fast
            # At the middle (in log H) of the table interval, where the stretch is.
            anchors.append(points[int(np.argmin(np.abs(np.log(height) - 0.5 * np.log(low_row * high_row))))])
            labels.append(f"{low_row:g} to {high_row:g} m: {DERIVATIVE_MATHTEXT.get(coefficient, coefficient)} "
                          f"{below:g} → {above:g}".replace("-", "−"))
        _place_labels(fig, ax, points, anchors, labels, taken)
    name = _save(fig, outdir, "root_locus.png")
    caption = (f"Eigenvalues of Eq. (1) at {len(height)} heights of {os.path.basename(archive.path)} "
               f"(study {archive.study_name}) at u0 = {speed:.6g} m/s"
               + (" (the paper's speed)" if at_paper_speed else
                  f", the nearest of its speeds to the paper's {PAPER_SPEED_MPS} m/s (no archive of this report "
                  f"has at least {LOCUS_DENSE_HEIGHTS} heights at exactly that speed)")
               + ", coloured by height (conjugates omitted). The red cross marks the lowest height, the star the "
                 "highest.")
    if fast is not None:
        low_row, high_row, coefficient, below, above, _ = fast
        caption += (f" The dotted straight stretch of the short-period locus lies between the table rows at "
                    f"{low_row:g} m and {high_row:g} m, where {DERIVATIVE_NAMES.get(coefficient, coefficient)} "
                    f"jumps from {below:g} to {above:g} (the aircraft file's table, the paper's Table A2). The "
                    f"coefficients are interpolated linearly between rows, so over that height interval the root "
                    f"moves far and nearly straight, and the heights, evenly spaced in log H, land far apart on it.")
    if archive.aircraft.table_heights_m and height[-1] >= archive.aircraft.table_heights_m[-1]:
        caption += (f" At and above the last table row ({archive.aircraft.table_heights_m[-1]:g} m) the coefficients "
                    f"are the free-flight row, so the star is the free-flight end of the locus.")
    return [Figure(name, "Root locus against height", caption)]


def _distinct_styles(n):
    """n (colour, line style) pairs told apart at a glance (a sequential map makes neighbouring start
    heights look alike): Matplotlib's qualitative tab10, solid, then dashed beyond ten."""
    return [(plt.get_cmap("tab10")(i % 10), "-" if i < 10 else "--") for i in range(n)]


def open_loop(archives, outdir):
    figures = []
    for archive in archives:
        if not archive.has(OPEN_LOOP_HEIGHT):
            continue
        height0 = archive.param("height_m")
        rows = np.nonzero(archive.complete)[0]
        rows = rows[np.argsort(height0[rows], kind="stable")]
        if len(rows) == 0:
            continue
        if len(rows) > MAX_OPEN_LOOP_LINES:
            rows = rows[np.linspace(0, len(rows) - 1, MAX_OPEN_LOOP_LINES).round().astype(int)]
        time = archive.file[OPEN_LOOP_TIME][...]
        series = archive.series(OPEN_LOOP_HEIGHT, rows)
        groups = {int(r): key for key, members in archive.groups(("height_m",)) for r in members}
        b = archive.aircraft.wingspan_m
        wheel = archive.aircraft.wheel_contact_height_m
        speed = archive.param("speed_mps")
        amplitude = archive.param("pulse_amplitude_deg")
        duration = archive.param("pulse_duration_s")
        fig, (left, right, legend_axis) = plt.subplots(1, 3, figsize=(13, 4.9), layout="constrained",
                                                       gridspec_kw={"width_ratios": [1.6, 1, 0.62]})
        axes = (left, right)
        styles = _distinct_styles(len(rows))
        colors = [colour for colour, _ in styles]
        for ax, t_max in ((axes[0], time[-1]), (axes[1], min(10.0, time[-1]))):
            for (color, line_style), row, h in zip(styles, rows, series):
                label = f"H0 = {height0[row]:.5g} m"
                if b > 0:
                    label += f" (H/b {height0[row] / b:.2f})"
                extra = _h_derivatives_label(archive, groups.get(int(row), {}))
                if extra:
                    label += ", " + extra
                ax.plot(time, h, color=color, ls=line_style, lw=1.3, label=label)
                finite = np.nonzero(np.isfinite(h))[0]
                if len(finite) and finite[-1] < len(h) - 1:
                    ax.plot(time[finite[-1]], h[finite[-1]], "x", color=color, ms=7, mew=1.6)
            if wheel > 0:
                ax.axhline(wheel, color=WHEEL_COLOUR_OPEN_LOOP, lw=1.6)
            if b > 0:
                ax.axhline(0.5 * b, color="#00a000", ls="--", lw=1.1)
            ax.set_xlim(0, t_max)
            ax.set_ylim(0, max(np.nanmax(series), np.nanmax(height0[rows])) * 1.05)
            ax.set_xlabel("time t (s)")
            ax.set_ylabel("height H (m)")
            ax.grid(alpha=0.3)
        # The runs still airborne at the end are named at their ends: their lines overlap most.
        ends = [(h[-1], f"{height0[row]:.5g} m", color) for color, row, h in zip(colors, rows, series)
                if np.isfinite(h[-1])]
        gap = OPEN_LOOP_END_LABEL_GAP * (axes[0].get_ylim()[1] - axes[0].get_ylim()[0])
        placed = []
        for y, text, color in sorted(ends):
            y_label = max([y] + [p + gap for p in placed[-1:]])
            placed.append(y_label)
            axes[0].annotate(text, (time[-1], y_label), xytext=(4, 0), textcoords="offset points",
                             annotation_clip=False, fontsize=8, color=color, va="center", ha="left")
        _span_axis(axes[1], b)
        axes[0].set_title("whole run")
        axes[1].set_title("first 10 s")
        handles, labels = axes[0].get_legend_handles_labels()
        handles += [Line2D([], [], color=WHEEL_COLOUR_OPEN_LOOP, lw=1.6), Line2D([], [], color="#00a000", ls="--"),
                    Line2D([], [], color="k", marker="x", ls="")]
        labels += [f"wheel contact ({wheel:.3g} m)", "H/b = 0.5", "end of the run (touchdown, stall, divergence)"]
        legend_axis.axis("off")
        legend_axis.legend(handles, labels, loc="center left", fontsize=8, borderaxespad=0)
        condition = ""
        if speed is not None and amplitude is not None and duration is not None:
            condition = (f"u0 = {speed[rows[0]]:.6g} m/s, elevator pulse {amplitude[rows[0]]:+g}° for "
                         f"{duration[rows[0]]:g} s")
        fig.suptitle(f"Open-loop height response ({condition})")
        name = _save(fig, outdir, f"open_loop_{_slug(archive.study_name)}.png")
        figures.append(Figure(name, f"Open-loop height histories ({archive.study_name})",
                              f"Height against time after the elevator pulse, from each start height of "
                              f"{os.path.basename(archive.path)} (the paper's Fig. 4 study when it is "
                              f"paper_fig4_open_loop), one colour per start height. A cross ends a run before the "
                              f"time limit; the runs still airborne at the end are named by their start height at the "
                              f"right of the whole-run panel."))
    return figures


def landing(archives, outdir):
    figures = []
    for archive in archives:
        if not archive.has(LANDING_SERIES["height_m"]):
            continue
        rows = np.nonzero(archive.complete)[0][:MAX_LANDING_LINES]
        if len(rows) == 0:
            continue
        time = archive.file[LANDING_TIME][...]
        data = {name: archive.series(path, rows) for name, path in LANDING_SERIES.items()}
        groups = {int(r): key for key, members in archive.groups(()) for r in members}
        fig, axes = plt.subplots(2, 2, figsize=(12, 8), layout="constrained")
        styles = ["-", "--", "-.", ":"]
        colors = ["#1f4e9c", "#d2541c", "#2a9d3a", "#8e44ad", "#555555", "#b8860b"]
        for i, row in enumerate(rows):
            label = _h_derivatives_label(archive, groups.get(int(row), {})) or f"run {row}"
            style = dict(color=colors[i % len(colors)], ls=styles[i % len(styles)], lw=1.6 if i == 0 else 1.3,
                         label=label)
            h = data["height_m"][i]
            x = data["distance_past_transmitter_m"][i]
            axes[0, 0].plot(x, h, **style)
            near = h < 15.0
            axes[0, 1].plot(x[near], h[near], **style)
            axes[1, 0].plot(time, np.degrees(data["elevator_rad"][i]), **style)
            axes[1, 1].plot(time, np.degrees(data["pitch_rate_radps"][i]), **style)
        wheel = archive.aircraft.wheel_contact_height_m
        for ax in (axes[0, 0], axes[0, 1]):
            if wheel > 0:
                ax.axhline(wheel, color="saddlebrown", lw=1.2, label=f"wheel contact ({wheel:.3g} m)")
            ax.set_xlabel("distance past the glide-slope transmitter (m)")
            ax.set_ylabel("height H (m)")
        b = archive.aircraft.wingspan_m
        if b > 0:
            axes[0, 1].axhline(0.5 * b, color="#00a000", ls="--", lw=1.0, label="H/b = 0.5")
        axes[0, 0].set_title("flight path")
        axes[0, 1].set_title("flare and touchdown (H < 15 m)")
        axes[1, 0].set_title("elevator deflection δe")
        axes[1, 0].set_ylabel("δe (deg, trailing edge down positive)")
        axes[1, 1].set_title("pitch rate q")
        axes[1, 1].set_ylabel("q (deg/s)")
        for ax in (axes[1, 0], axes[1, 1]):
            ax.set_xlabel("time t (s)")
        for ax in axes.flat:
            ax.grid(alpha=0.3)
        axes[0, 1].legend(loc="upper right")
        axes[0, 0].legend(loc="upper right")
        speed = archive.param("speed_mps")
        start = archive.param("height_m")
        fig.suptitle(f"Automatic landing from {start[rows[0]]:g} m at {speed[rows[0]]:g} m/s" if speed is not None
                     and start is not None else "Automatic landing")
        name = _save(fig, outdir, f"landing_{_slug(archive.study_name)}.png")
        figures.append(Figure(name, f"Landing trajectories ({archive.study_name})",
                              "Height against distance, and elevator and pitch rate against time, of each run of "
                              f"{os.path.basename(archive.path)} (the paper's Fig. 6-9 compare the landing with and "
                              "without the h-derivatives)."))
    return figures


def sensitivity(archives, outdir):
    figures = []
    for archive in archives:
        for path in archive.analysis_groups("analysis/sensitivity"):
            group = archive.file[path]
            attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in group.attrs.items()}
            method = str(attrs.get("method"))
            parameters = [p.decode() if isinstance(p, bytes) else str(p) for p in attrs.get("parameters", [])]
            output = str(attrs.get("output", path.split("analysis/sensitivity/")[-1]))
            level = float(attrs.get("confidence_level", 0.95)) * 100
            x = np.arange(len(parameters))
            fig, ax = plt.subplots(figsize=(max(6.0, 0.75 * len(parameters) + 3), 4.4), layout="constrained")
            if method == "sobol" and "first_order" in group and "total" in group:
                bars = [("first_order", "first order S_i", "#1f77b4"), ("total", "total S_Ti", "#ff7f0e")]
                ylabel = "Sobol' index (1)"
                title = f"Sobol' indices of {output} (N = {attrs.get('n', '?')} base samples)"
            elif method == "morris" and "mu_star" in group:
                bars = [("mu_star", "μ* (mean |elementary effect|)", "#1f77b4"), ("sigma", "σ of the effects", "#aaaaaa")]
                ylabel = f"effect on {output} ({group['mu_star'].attrs.get('units', '')})"
                title = f"Morris elementary effects of {output} ({attrs.get('n', '?')} trajectories)"
            else:
                plt.close(fig)
                continue
            width = 0.8 / len(bars)
            for i, (dataset, label, color) in enumerate(bars):
                if dataset not in group:
                    continue
                values = group[dataset][...]
                error = None
                if dataset + "_ci" in group:
                    ci = group[dataset + "_ci"][...]
                    error = np.vstack([np.clip(values - ci[:, 0], 0, None), np.clip(ci[:, 1] - values, 0, None)])
                ax.bar(x + (i - (len(bars) - 1) / 2) * width, values, width, yerr=error, capsize=3, color=color,
                       label=label + (f" with {level:g} % interval" if error is not None else ""))
            ax.axhline(0, color="k", lw=0.8)
            ax.set_xticks(x)
            ax.set_xticklabels(parameters, rotation=30, ha="right")
            ax.set_xlabel("parameter")
            ax.set_ylabel(ylabel)
            ax.set_title(title)
            ax.legend()
            ax.grid(axis="y", alpha=0.3)
            name = _save(fig, outdir, f"sensitivity_{_slug(archive.study_name)}_{_slug(output)}.png")
            figures.append(Figure(name, f"Sensitivity of {output} ({archive.study_name})",
                                  f"From {path} of {os.path.basename(archive.path)}: bars with bootstrap "
                                  f"confidence intervals (docs/sensitivity.md)."))
    return figures


def _text(value):
    return value.decode() if isinstance(value, bytes) else str(value)


def dispersion(archives, outdir):
    """From /analysis/dispersion (gesweep dispersion, docs/dispersion.md): the empirical CDF of each
    dispersion column per group, the touchdown footprint (sink rate against distance past the
    transmitter) when both columns are there, and each limit's probability against the grouping
    value with its Clopper-Pearson interval."""
    figures = []
    status_path = columns.runs_path("status")
    distance = columns.path("landing", "touchdown_distance_past_transmitter_m")
    sink = columns.path("landing", "touchdown_sink_rate_mps")
    for archive in archives:
        if "analysis/dispersion" not in archive.file:
            continue
        product = archive.file["analysis/dispersion"]
        attrs = {k: product.attrs[k] for k in product.attrs}
        paths = [_text(p) for p in attrs.get("column_paths", [])]
        names = [_text(p) for p in attrs.get("columns", [])]
        units = [_text(p) for p in attrs.get("column_units", [])]
        group_path = _text(attrs.get("group_path", ""))
        group_by = _text(attrs.get("group_by", ""))
        labels = [_text(v) for v in product["group_label"][...]]
        keys = product["group_value"][...]
        ok = archive.file[status_path][...] == 1
        grouping = archive.file[group_path][...] if group_path and group_path in archive.file else None

        def members(index):
            if grouping is None:
                return ok
            return ok & (np.isnan(grouping) if np.isnan(keys[index]) else grouping == keys[index])

        if paths:
            fig, axes = plt.subplots(1, len(paths), figsize=(4.2 * len(paths), 3.8), layout="constrained",
                                     squeeze=False)
            for ax, path, name, unit in zip(axes[0], paths, names, units):
                values = archive.file[path][...]
                for g, label in enumerate(labels):
                    sample = np.sort(values[members(g) & np.isfinite(values)])
                    if sample.size:
                        ax.step(sample, np.arange(1, sample.size + 1) / sample.size, where="post",
                                label=(f"{group_by} = {label}" if group_by else "all runs") + f" (n = {sample.size})")
                ax.set_xlabel(f"{name} ({unit})")
                ax.set_ylabel("fraction of runs at or below")
                ax.grid(alpha=0.3)
            axes[0][0].legend(fontsize="small")
            name = _save(fig, outdir, f"dispersion_{_slug(archive.study_name)}_ecdf.png")
            figures.append(Figure(name, f"Dispersion of {archive.study_name}: empirical CDFs",
                                  "Each column of /analysis/dispersion over the complete runs with a value, "
                                  "one curve per group (docs/dispersion.md)."))
        if distance in archive.file and sink in archive.file:
            x, y = archive.file[distance][...], archive.file[sink][...]
            fig, ax = plt.subplots(figsize=(6.4, 4.6), layout="constrained")
            for g, label in enumerate(labels):
                m = members(g) & np.isfinite(x) & np.isfinite(y)
                ax.scatter(x[m], y[m], s=6, alpha=0.6, label=(f"{group_by} = {label}" if group_by else "all runs"))
            ax.set_xlabel(f"touchdown distance past the transmitter ({columns.units('landing', 'touchdown_distance_past_transmitter_m')})")
            ax.set_ylabel(f"touchdown sink rate ({columns.units('landing', 'touchdown_sink_rate_mps')})")
            ax.grid(alpha=0.3)
            ax.legend(fontsize="small")
            name = _save(fig, outdir, f"dispersion_{_slug(archive.study_name)}_footprint.png")
            figures.append(Figure(name, f"Touchdown footprint of {archive.study_name}",
                                  "Sink rate against distance past the transmitter at touchdown, one point per "
                                  "complete run."))
        limits = product.get("limits")
        if limits is not None and "probability" in limits and limits["probability"].shape[1] and group_by:
            order = np.argsort(keys)
            fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
            for l, text in enumerate(_text(t) for t in limits["limit"][...]):
                p = limits["probability"][...][order, l]
                low = limits["clopper_pearson_lower"][...][order, l]
                high = limits["clopper_pearson_upper"][...][order, l]
                ax.errorbar(keys[order], p, yerr=np.vstack([p - low, high - p]), marker="o", capsize=3, label=text)
            ax.set_xticks(keys[order], [labels[i] for i in order])  # level names for a choice or flag
            ax.set_xlabel(f"{group_by} ({_text(attrs.get('group_units', ''))})")
            ax.set_ylabel("probability of exceeding the limit")
            ax.grid(alpha=0.3)
            ax.legend(fontsize="small")
            level = float(attrs.get("confidence_level", 0.95)) * 100
            name = _save(fig, outdir, f"dispersion_{_slug(archive.study_name)}_limits.png")
            figures.append(Figure(name, f"Limit exceedance against {group_by} ({archive.study_name})",
                                  f"Empirical probability per group with its {level:g} % Clopper-Pearson interval "
                                  "(e.g. a hard landing against the wind level)."))
    return figures
