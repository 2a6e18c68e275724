"""The open-loop height histories (the paper's Fig. 4; docs/report.md, "The other figures")."""

import os

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D

import figures_common as common  # (first: it puts scripts/lib on the path)
import columns  # scripts/lib/columns.py
import report_labels
from figures_common import Figure

OPEN_LOOP_HEIGHT = columns.path("open_loop", "height_m", series=True)
OPEN_LOOP_TIME = columns.time_axis("open_loop")
MAX_OPEN_LOOP_LINES = 12
# The open-loop lines take tab10's colours, its brown too: the wheel-contact line there is black.
WHEEL_COLOUR_OPEN_LOOP = "k"
# Names at the ends of the open-loop lines are at least this fraction of the height axis apart.
OPEN_LOOP_END_LABEL_GAP = 0.045


def _distinct_styles(n):
    """n (colour, line style) pairs told apart at a glance (a sequential map makes neighbouring start
    heights look alike): Matplotlib's qualitative tab10, solid, then dashed beyond ten."""
    return [(plt.get_cmap("tab10")(i % 10), "-" if i < 10 else "--") for i in range(n)]


def draw(archives, outdir):
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
        figures.append(_histories(archive, rows, outdir))
    return figures


def _start_label(archive, key, height0):
    """A line's label: its start height (and H/b), and the other swept parameters of its group."""
    b = archive.aircraft.wingspan_m
    label = f"H0 = {report_labels.number(height0)} m" + (f" (H/b {height0 / b:.2f})" if b > 0 else "")
    extra = archive.key_text(key)
    return label + (", " + extra if extra else "")


def _histories(archive, rows, outdir):
    height0 = archive.param("height_m")
    time = archive.read(OPEN_LOOP_TIME)
    series = archive.series(OPEN_LOOP_HEIGHT, rows)
    groups = {int(r): key for key, members in archive.groups(("height_m",)) for r in members}
    b = archive.aircraft.wingspan_m
    wheel = archive.aircraft.wheel_contact_height_m
    fig, (left, right, legend_axis) = plt.subplots(1, 3, figsize=(common.PAGE_WIDTH_IN, 4.6), layout="constrained",
                                                   gridspec_kw={"width_ratios": [1.45, 1, 0.8]})
    axes = (left, right)
    styles = _distinct_styles(len(rows))
    for ax, t_max in ((axes[0], time[-1]), (axes[1], min(10.0, time[-1]))):
        for (color, line_style), row, h in zip(styles, rows, series):
            ax.plot(time, h, color=color, ls=line_style, lw=1.3,
                    label=_start_label(archive, groups.get(int(row), {}), height0[row]))
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
    _name_the_ends(axes[0], time, [(h[-1], report_labels.number(height0[row]) + " m", colour)
                                   for (colour, _), row, h in zip(styles, rows, series) if np.isfinite(h[-1])])
    common.span_axis(axes[1], b)
    axes[0].set_title("whole run")
    axes[1].set_title("first 10 s")
    handles, labels = axes[0].get_legend_handles_labels()
    handles += [Line2D([], [], color=WHEEL_COLOUR_OPEN_LOOP, lw=1.6), Line2D([], [], color="#00a000", ls="--"),
                Line2D([], [], color="k", marker="x", ls="")]
    labels += [f"wheel contact ({wheel:.3g} m)", "H/b = 0.5", "end of the run (touchdown, stall, divergence)"]
    legend_axis.axis("off")
    legend_axis.legend(handles, labels, loc="center left", fontsize=8.5, borderaxespad=0)
    fig.suptitle(f"Open-loop height response ({_condition(archive, rows[0])})")
    name = common.save(fig, outdir, f"open_loop_{common.slug(archive.study_name)}.png")
    return Figure(name, f"Open-loop height histories ({archive.study_name})",
                  f"Height against time after the elevator pulse, from each start height of "
                  f"{os.path.basename(archive.path)} (the paper's Fig. 4 study when it is paper_fig4_open_loop), one "
                  f"colour per start height. A cross ends a run before the time limit; the runs still airborne at "
                  f"the end are named by their start height at the right of the whole-run panel.")


def _name_the_ends(ax, time, ends):
    """Names the runs still airborne at the end at their ends (their lines overlap most), at least
    OPEN_LOOP_END_LABEL_GAP of the axis apart. `ends`: (last height, text, colour)."""
    gap = OPEN_LOOP_END_LABEL_GAP * (ax.get_ylim()[1] - ax.get_ylim()[0])
    placed = []
    for y, text, color in sorted(ends):
        y_label = max([y] + [p + gap for p in placed[-1:]])
        placed.append(y_label)
        ax.annotate(text, (time[-1], y_label), xytext=(4, 0), textcoords="offset points", annotation_clip=False,
                    fontsize=8, color=color, va="center", ha="left")


def _condition(archive, row):
    """The flight condition of the study's runs in words: "u0 = 32.02 m/s, elevator pulse +5° for 0.2 s"."""
    speed, amplitude = archive.param("speed_mps"), archive.param("pulse_amplitude_deg")
    duration = archive.param("pulse_duration_s")
    if speed is None or amplitude is None or duration is None:
        return ""
    return (f"{archive.value_text('speed_mps', speed[row])}, elevator pulse +{report_labels.number(amplitude[row])}° "
            f"for {report_labels.number(duration[row])} s").replace("+-", "−")
