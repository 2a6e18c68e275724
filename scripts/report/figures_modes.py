"""The root locus against height (docs/report.md, "Which runs the root locus draws"): the short-period
and phugoid roots and the height mode's real root as the height falls to wheel contact."""

import math
import os

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm, Normalize
from matplotlib.lines import Line2D
from matplotlib.text import Text

import figures_common as common  # (first: it puts scripts/lib on the path)
import columns  # scripts/lib/columns.py
from figures_common import PAPER_SPEED_MPS, Figure

MODE_EIGENVALUES = {  # (Re, Im) of each mode
    "short_period": (columns.path("modes", "short_period/eigenvalue_re_per_s"),
                     columns.path("modes", "short_period/eigenvalue_im_per_s")),
    "phugoid": (columns.path("modes", "phugoid/eigenvalue_re_per_s"),
                columns.path("modes", "phugoid/eigenvalue_im_per_s")),
    "height": (columns.path("modes", "height/eigenvalue_re_per_s"),
               columns.path("modes", "height/eigenvalue_im_per_s")),
}
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


def draw(archives, outdir):
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
    fig = plt.figure(figsize=(common.PAGE_WIDTH_IN, 5.2), layout="constrained")
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
    common.legend_row(fig, legend_axis, handles, ncols=len(handles))
    bar = fig.colorbar(scatter, ax=axes, pad=0.01, aspect=30)
    bar.set_label("height H (m)")
    others = {k: v for k, v in key.items() if k != "speed_mps"}
    if at_paper_speed:
        condition = f"{archive.value_text('speed_mps', speed)}, the paper's speed, "
    else:
        condition = f"{archive.value_text('speed_mps', speed)}, the speed of {archive.study_name} nearest the paper's, "
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
            labels.append(f"{low_row:g} to {high_row:g} m:\n{DERIVATIVE_MATHTEXT.get(coefficient, coefficient)} "
                          f"{below:g} → {above:g}".replace("-", "−"))
        _place_labels(fig, ax, points, anchors, labels, taken)
    name = common.save(fig, outdir, "root_locus.png")
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

