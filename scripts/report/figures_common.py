"""What every figure family of the report shares (docs/report.md, "The figure modules"): the Figure
record, matplotlib's settings, saving (with its observers), and the small helpers of the axes.

A figure family is one module `figures_<family>.py` with one public function
`draw(archives, outdir) -> [Figure]` per section it fills; report_figures.py lists them in page order.
"""

import os
import sys
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.transforms import blended_transform_factory  # noqa: E402

_LIB = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "lib")
if _LIB not in sys.path:
    sys.path.insert(0, _LIB)

DPI = 110
# The widest figure, in inches: at DPI it is 1155 px, the page's column at a 1400 px window (report.py's
# CSS), so no figure is scaled down to fit and every font keeps its size.
PAGE_WIDTH_IN = 10.5
# The paper's open-loop speed (Section IV); the claims, the root locus and the level maps refer to it.
PAPER_SPEED_MPS = 32.0208
# Heights spaced by a constant ratio to this relative tolerance are drawn on a log axis.
GEOMETRIC_SPACING_TOLERANCE = 1e-6
# At most this many figures of one kind per archive (one per value of the other swept parameters).
MAX_MAP_PANELS = 4
# A cell without a complete ok run.
MISSING_COLOUR = "#b0b0b0"

plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9,
                     "xtick.labelsize": 9, "ytick.labelsize": 9, "figure.dpi": DPI, "savefig.dpi": DPI})

# Called as observer(fig, name) on every figure just before it is saved (the tests read the artists
# of each figure as drawn through this; nothing in the report needs it).
observers = []


@dataclass
class Figure:
    file: str
    title: str
    caption: str


def save(fig, outdir, name):
    """Writes `fig` as outdir/name (PNG) and closes it; returns the name."""
    for observer in observers:
        observer(fig, name)
    # No bbox_inches="tight": it draws the figure twice; the figures use constrained layout instead.
    fig.savefig(os.path.join(outdir, name))
    plt.close(fig)
    return name


def slug(text):
    return "".join(c if c.isalnum() else "_" for c in text).strip("_").lower()


def geometric(values):
    """Whether the values are spaced by a constant ratio (then drawn on a log axis)."""
    values = np.asarray(values)
    if len(values) < 3 or np.any(values <= 0):
        return False
    ratios = values[1:] / values[:-1]
    return float(np.std(ratios) / np.mean(ratios)) < GEOMETRIC_SPACING_TOLERANCE


def span_axis(ax, wingspan_m):
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


def last_table_row_m(archive):
    """The height of the aircraft table's last finite row (m), or NaN."""
    rows = archive.aircraft.table_heights_m
    return float(rows[-1]) if rows else float("nan")


# A legend row uses at most this fraction of the figure's width (the rest is its margins).
LEGEND_WIDTH_FRACTION = 0.97


def legend_row(fig, legend_axis, handles, ncols):
    """The legend of `handles` in its own axis below the panels, centred on the figure, in `ncols`
    columns, or in fewer when that many would be wider than the figure (a centred legend wider than
    its figure loses both ends)."""
    legend_axis.axis("off")
    renderer = fig.canvas.get_renderer()
    # Centred on the figure across (the axis may sit left of a colour bar), on the axis up and down.
    anchor = blended_transform_factory(fig.transFigure, legend_axis.transAxes)
    for columns in range(max(1, ncols), 0, -1):
        legend = legend_axis.legend(handles=handles, loc="center", ncols=columns, frameon=False,
                                    bbox_to_anchor=(0.5, 0.5), bbox_transform=anchor)
        if columns == 1 or legend.get_window_extent(renderer).width <= LEGEND_WIDTH_FRACTION * fig.bbox.width:
            return legend
        legend.remove()
    return legend
