"""The landing trajectories (the paper's Fig. 6-9; docs/report.md, "The other figures"): the paper's
landing study, not the dispersion studies, which have their own section."""

import os

import matplotlib.pyplot as plt
import numpy as np

import figures_common as common  # (first: it puts scripts/lib on the path)
import columns  # scripts/lib/columns.py
import report_labels
from figures_common import Figure

LANDING_TIME = columns.time_axis("landing")
LANDING_SERIES = {
    "height_m": columns.path("landing", "height_m", series=True),
    "distance_past_transmitter_m": columns.path("landing", "distance_past_transmitter_m", series=True),
    "elevator_rad": columns.path("landing", "elevator_rad", series=True),
    "pitch_rate_radps": columns.path("landing", "pitch_rate_radps", series=True),
}
MAX_LANDING_LINES = 6


def draw(archives, outdir):
    """The trajectories of each landing archive that is not a dispersion study (those have their own
    section, figures_dispersion)."""
    figures = []
    for archive in archives:
        if not archive.has(LANDING_SERIES["height_m"]) or archive.is_dispersion():
            continue
        rows = np.nonzero(archive.complete)[0][:MAX_LANDING_LINES]
        if len(rows) > 0:
            figures.append(_trajectories(archive, rows, outdir))
    return figures


def _trajectories(archive, rows, outdir):
    time = archive.read(LANDING_TIME)
    data = {name: archive.series(path, rows) for name, path in LANDING_SERIES.items()}
    groups = {int(r): key for key, members in archive.groups(()) for r in members}
    fig, axes = plt.subplots(2, 2, figsize=(common.PAGE_WIDTH_IN, 7.4), layout="constrained")
    styles = ["-", "--", "-.", ":"]
    colors = ["#1f4e9c", "#d2541c", "#2a9d3a", "#8e44ad", "#555555", "#b8860b"]
    for i, row in enumerate(rows):
        label = archive.key_text(groups.get(int(row), {})) or f"run {row}"
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
    speed, start = archive.param("speed_mps"), archive.param("height_m")
    fig.suptitle(f"Automatic landing from {report_labels.number(start[rows[0]])} m at "
                 f"{report_labels.number(speed[rows[0]])} m/s" if speed is not None and start is not None
                 else "Automatic landing")
    name = common.save(fig, outdir, f"landing_{common.slug(archive.study_name)}.png")
    return Figure(name, f"Landing trajectories ({archive.study_name})",
                  "Height against distance, and elevator and pitch rate against time, of each run of "
                  f"{os.path.basename(archive.path)} (the paper's Fig. 6-9 compare the landing with and without the "
                  "h-derivatives).")
