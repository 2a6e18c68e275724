"""The stability map (docs/report.md, "What the stability map shows"): σ over height x speed and the
phugoid's own real part, with every line drawn over a height x speed map (map_overlays) and its axes
(map_axes), which the level maps share."""

import os

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import SymLogNorm
from matplotlib.lines import Line2D

import figures_common as common  # (first: it puts scripts/lib on the path)
import columns  # scripts/lib/columns.py
import report_labels
from figures_common import MAX_MAP_PANELS, MISSING_COLOUR, Figure

# The columns the map reads (the column manifest; a renamed column fails here, at import).
SIGMA = columns.path("modes", "stability_margin_per_s")
SIGMA_UNITS = columns.units("modes", "stability_margin_per_s")
PHUGOID_RE = columns.path("modes", "phugoid/eigenvalue_re_per_s")
HEIGHT_RE = columns.path("modes", "height/eigenvalue_re_per_s")
# The stability map's colour scale is linear within ±this and logarithmic beyond (1/s): a phugoid
# doubling in about 12 min is still visibly red.
SIGMA_LINEAR_PER_S = 1e-3


def draw(archives, outdir):
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


def height_speed_grid(archive, rows, heights, speeds, path):
    """A per-run column on the heights x speeds grid of `rows` (NaN where no ok run)."""
    grid = np.full((len(heights), len(speeds)), np.nan)
    height, speed = archive.param("height_m")[rows], archive.param("speed_mps")[rows]
    grid[np.searchsorted(heights, height), np.searchsorted(speeds, speed)] = archive.column(path)[rows]
    return grid


def _stability_map(archive, key, rows, outdir, number):
    """The stability map of one group of runs: σ over height x speed and, when the archive has it, the
    phugoid's own real part on the same colour scale; every line of the map is drawn by
    map_overlays."""
    heights, speeds = np.unique(archive.param("height_m")[rows]), np.unique(archive.param("speed_mps")[rows])
    if len(heights) < 2 or len(speeds) < 2:
        return None
    sigma = height_speed_grid(archive, rows, heights, speeds, SIGMA)
    panels = [(sigma, "σ = 0 on the grid", "stability margin σ: the largest Re λ, the exactly neutral height root left out")]
    phugoid = None
    if archive.has(PHUGOID_RE):
        phugoid = height_speed_grid(archive, rows, heights, speeds, PHUGOID_RE)
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
        for handle in map_overlays(ax, archive, key, heights, speeds, grid, zero_label):
            handles.setdefault(handle.get_label(), handle)
        map_axes(ax, archive, heights, speeds)
        ax.set_title(title)
    for ax in axes[:-2]:
        ax.set_xlabel("")
    bar = fig.colorbar(mesh, ax=list(axes[:-1]), pad=0.02, aspect=35)
    bar.set_label(f"σ, Re λ ({SIGMA_UNITS}): red unstable (> 0), blue stable (< 0)")
    common.legend_row(fig, legend_axis, list(handles.values()), ncols=2)
    suffix = f" ({archive.key_text(key)})" if key else ""
    fig.suptitle(f"{archive.aircraft.name or 'aircraft'}: stability over height and speed{suffix}")
    name = common.save(fig, outdir, f"stability_map_{common.slug(archive.study_name)}_{number}.png")
    return Figure(name, f"Stability map ({archive.study_name}){suffix}",
                  _map_caption(archive, rows, heights, speeds, sigma, phugoid))


def map_overlays(ax, archive, key, heights, speeds, grid, zero_label):
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
    traced = archive.boundary_curve() if len(key) == 0 else None
    if traced is not None:
        branches = traced["branch"]
        for branch in np.unique(branches):
            on = branches == branch
            ax.plot(traced["speed_mps"][on], traced["height_m"][on], color="#ff00c8", lw=1.4)
        if len(branches):
            handles.append(Line2D([], [], color="#ff00c8", lw=1.4,
                                  label="H*(u0) traced by continuation (/analysis/boundary_curve)"))
    if b > 0:
        ax.axhline(0.5 * b, color="#00a000", ls="--", lw=1.4)
        handles.append(Line2D([], [], color="#00a000", ls="--", lw=1.4,
                              label=f"H/b = 0.5 ({report_labels.number(0.5 * b)} m): the paper's boundary"))
    wheel = archive.aircraft.wheel_contact_height_m
    if wheel > 0 and heights[0] <= wheel <= heights[-1]:
        ax.axhline(wheel, color="saddlebrown", lw=1.2)
        handles.append(Line2D([], [], color="saddlebrown", lw=1.2, label=f"wheel contact ({wheel:.3g} m)"))
    last_row = common.last_table_row_m(archive)
    if heights[0] < last_row < heights[-1]:
        ax.axhline(last_row, color="0.25", ls=":", lw=1.2)
        handles.append(Line2D([], [], color="0.25", ls=":", lw=1.2,
                              label=f"last table row ({report_labels.number(last_row)} m): free-flight coefficients above"))
    return handles


def map_axes(ax, archive, heights, speeds):
    if common.geometric(heights):
        ax.set_yscale("log")
        ticks = [t for t in (0.8, 1, 1.5, 2, 3, 4, 5, 7, 10, 14, 20, 30, 50) if heights[0] <= t <= heights[-1]]
        ax.set_yticks(ticks)
        ax.set_yticklabels([f"{t:g}" for t in ticks])
        ax.minorticks_off()
    ax.set_xlim(speeds[0], speeds[-1])
    ax.set_ylim(heights[0], heights[-1])
    common.span_axis(ax, archive.aircraft.wingspan_m)
    ax.set_xlabel("reference speed u0 (m/s)")
    ax.set_ylabel("height H of the mean chord (m)")


def _map_caption(archive, rows, heights, speeds, sigma, phugoid):
    text = (f"Eigen-analysis of Eq. (1) over {len(speeds)} speeds × {len(heights)} heights ({len(rows)} runs of "
            f"{os.path.basename(archive.path)}). Colours are centred on 0 (white), linear within "
            f"±{SIGMA_LINEAR_PER_S:g} 1/s and logarithmic beyond, one scale for both panels; grey cells have no "
            f"complete ok run. The yellow curve, where present, is the boundary H* refined on the continuous "
            f"model by gesweep boundary --archive.")
    if phugoid is None:
        return text
    height_root = (height_speed_grid(archive, rows, heights, speeds, HEIGHT_RE)
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
    last_row = common.last_table_row_m(archive)
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

