"""The dispersion figures, from /analysis/dispersion (gesweep dispersion, docs/dispersion.md): the
empirical CDF of each dispersion column per group, one panel per column in a grid of at most
MAX_COLUMNS columns; the touchdown footprint (sink rate against distance past the transmitter) when
both columns are there; and each limit's probability per group with its Clopper-Pearson interval.
Every group is named by report_labels ("W20 = 30 kt headwind"), never by its stored float."""

import math
import os
import re
import textwrap

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D

import figures_common as common  # (first: it puts scripts/lib on the path)
import columns  # scripts/lib/columns.py
from figures_common import Figure

DISTANCE = columns.path("landing", "touchdown_distance_past_transmitter_m")
SINK_RATE = columns.path("landing", "touchdown_sink_rate_mps")
# The ECDF grid has at most this many columns of panels (each about 3.5 in wide at the page's width).
MAX_COLUMNS = 3
# Height of one row of ECDF panels (in).
PANEL_HEIGHT_IN = 3.1
# A column's name ends in its unit (docs/architecture.md, "Describe once"); a panel's title drops it.
UNIT_SUFFIXES = ("_mps", "_radps", "_deg", "_rad", "_m", "_s", "_kg")
# The groups' colours and markers, in group order (tab10, the report's qualitative palette).
GROUP_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
# A limit's name is wrapped to lines of this many characters under its tick.
LIMIT_LABEL_WIDTH = 24
# A limit as `gesweep dispersion --limit` takes it: column, comparison, value.
LIMIT = re.compile(r"^\s*(?P<column>[\w/.]+)\s*(?P<op>>=|<=|>|<)\s*(?P<value>\S+)\s*$")


def draw(archives, outdir):
    figures = []
    for archive in archives:
        product = archive.dispersion()
        if product is None:
            continue
        groups = _groups(archive, product)
        if product["column_paths"]:
            figures.append(_ecdf_grid(archive, product, groups, outdir))
        if archive.has(DISTANCE) and archive.has(SINK_RATE):
            figures.append(_footprint(archive, groups, outdir))
        limits = product["limits"]
        if limits is not None and limits["probability"].shape[1] and product["group_by"]:
            figures.append(_limits(archive, product, groups, outdir))
    return figures


def _groups(archive, product):
    """(label in words, ok runs of the group) per group of the product, in the product's order."""
    name = product["group_by"]
    out = []
    for g, value in enumerate(product["values"]):
        if not name:
            label = "all runs"
        elif math.isnan(value):
            label = f"runs without a value of {name}"
        else:
            label = archive.value_text(name, value)
        out.append((label, product["members"](g)))
    return out


def quantity_title(name):
    """A column's name as a panel title: its unit suffix dropped, words apart."""
    for suffix in UNIT_SUFFIXES:
        if name.endswith(suffix):
            name = name[: -len(suffix)]
            break
    return name.replace("_", " ")


def limit_label(text, product):
    """A limit in words: "touchdown sink rate > 1.83 m/s" for touchdown_sink_rate_mps>1.83 (the unit
    from the product's column units), wrapped for a tick; the text as typed when it does not parse."""
    match = LIMIT.match(text)
    if not match:
        return textwrap.fill(text, LIMIT_LABEL_WIDTH)
    column = match["column"].split("/")[-1]
    units = dict(zip(product["columns"], product["column_units"]))
    unit = units.get(column, "")
    unit = "°" if unit == "deg" else ("" if unit in ("", "1") else " " + unit)
    return textwrap.fill(f"{quantity_title(column)} {match['op']} {match['value']}{unit}", LIMIT_LABEL_WIDTH,
                         break_long_words=False)


def _colour(index):
    return plt.get_cmap("tab10")(index % 10)


def _ecdf_grid(archive, product, groups, outdir):
    paths, names, units = product["column_paths"], product["columns"], product["column_units"]
    count = len(paths)
    ncols = min(MAX_COLUMNS, count)
    nrows = math.ceil(count / ncols)
    fig = plt.figure(figsize=(common.PAGE_WIDTH_IN, PANEL_HEIGHT_IN * nrows + 0.7), layout="constrained")
    grid = fig.add_gridspec(nrows + 1, ncols, height_ratios=[1] * nrows + [0.16])
    handles = {}
    for index, (path, name, unit) in enumerate(zip(paths, names, units)):
        ax = fig.add_subplot(grid[index // ncols, index % ncols])
        values = archive.read(path)
        for g, (label, members) in enumerate(groups):
            sample = np.sort(values[members & np.isfinite(values)])
            if sample.size:
                (line,) = ax.step(sample, np.arange(1, sample.size + 1) / sample.size, where="post", color=_colour(g),
                                  lw=1.5)
                handles.setdefault(g, Line2D([], [], color=_colour(g), lw=1.5, label=f"{label} (n = {sample.size})"))
        ax.set_title(quantity_title(name))
        ax.set_xlabel(unit if unit and unit != "1" else "value")
        if index % ncols == 0:
            ax.set_ylabel("fraction of runs at or below")
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
    legend_axis = fig.add_subplot(grid[nrows, :])
    common.legend_row(fig, legend_axis, [handles[g] for g in sorted(handles)], ncols=min(4, len(handles)))
    name = common.save(fig, outdir, f"dispersion_{common.slug(archive.study_name)}_ecdf.png")
    by = f", one curve per group of {product['group_by']}" if product["group_by"] else ""
    return Figure(name, f"Dispersion of {archive.study_name}: empirical CDFs",
                  f"Each column of /analysis/dispersion of {os.path.basename(archive.path)} over the complete ok "
                  f"runs with a value{by} (docs/dispersion.md).")


def _footprint(archive, groups, outdir):
    x, y = archive.column(DISTANCE), archive.column(SINK_RATE)
    fig, ax = plt.subplots(figsize=(7.6, 4.8), layout="constrained")
    for g, (label, members) in enumerate(groups):
        m = members & np.isfinite(x) & np.isfinite(y)
        ax.scatter(x[m], y[m], s=7, alpha=0.6, color=_colour(g), label=f"{label} (n = {int(m.sum())})")
    ax.set_xlabel(f"touchdown distance past the transmitter ({columns.units('landing', 'touchdown_distance_past_transmitter_m')})")
    ax.set_ylabel(f"touchdown sink rate ({columns.units('landing', 'touchdown_sink_rate_mps')})")
    ax.grid(alpha=0.3)
    ax.legend(markerscale=2.5)
    name = common.save(fig, outdir, f"dispersion_{common.slug(archive.study_name)}_footprint.png")
    return Figure(name, f"Touchdown footprint of {archive.study_name}",
                  "Sink rate against distance past the transmitter at touchdown, one point per complete ok run.")


def _limits(archive, product, groups, outdir):
    """Each limit's probability per group on a log scale, with its Clopper-Pearson interval; a count of
    0 is drawn as its interval's upper bound (a triangle pointing down), which is all it supports."""
    limits = product["limits"]
    texts = [str(t) for t in limits["limit"]]
    p, low, high = limits["probability"], limits["clopper_pearson_lower"], limits["clopper_pearson_upper"]
    fig, ax = plt.subplots(figsize=(common.PAGE_WIDTH_IN * 0.8, 4.8), layout="constrained")
    x = np.arange(len(texts))
    width = 0.7 / max(1, len(groups))
    for g, (label, _) in enumerate(groups):
        at = x + (g - (len(groups) - 1) / 2) * width
        seen = p[g] > 0
        ax.errorbar(at[seen], p[g][seen], yerr=np.vstack([p[g][seen] - low[g][seen], high[g][seen] - p[g][seen]]),
                    ls="", marker=GROUP_MARKERS[g % len(GROUP_MARKERS)], color=_colour(g), capsize=3, label=label)
        ax.plot(at[~seen], high[g][~seen], ls="", marker="v", color=_colour(g), ms=8)
    finite = np.concatenate([low[p > 0], high[p == 0]])
    finite = finite[finite > 0]
    ax.set_yscale("log")
    ax.set_ylim(10 ** math.floor(math.log10(finite.min())) if finite.size else 1e-4, 1.5)
    ax.set_xticks(x, [limit_label(t, product) for t in texts])
    ax.set_xlim(-0.5, len(texts) - 0.5)
    ax.set_ylabel("probability of the event")
    ax.grid(alpha=0.3, which="major")
    handles, labels = ax.get_legend_handles_labels()
    handles.append(Line2D([], [], ls="", marker="v", color="0.3", ms=8))
    labels.append("no run: the interval's upper bound")
    ax.legend(handles, labels)
    level = float(product["attrs"].get("confidence_level", 0.95)) * 100
    name = common.save(fig, outdir, f"dispersion_{common.slug(archive.study_name)}_limits.png")
    return Figure(name, f"Limit exceedance per group of {product['group_by']} ({archive.study_name})",
                  f"Empirical probability of each limit per group with its {level:g} % Clopper-Pearson interval; "
                  f"where no run of a group reaches a limit, the triangle is the interval's upper bound.")
