"""The report's figures (docs/report.md, "gesweep report"). Each function draws a figure only when the
archives hold its data, and returns a list of Figure records (file name, title, caption)."""

import math
import os
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, Normalize, SymLogNorm  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from report_data import STATUS_OK  # noqa: E402

# The paper's open-loop speed (Section IV): the root locus prefers the runs nearest to it.
PAPER_SPEED_MPS = 32.0208
# Runs within this of the paper's speed are as good as at it for the root locus; among them, the
# densest in height wins.
LOCUS_SPEED_WINDOW_MPS = 0.5
# Runs of two archives are at the same speed when within this (studies store 32.0208 exactly).
SAME_SPEED_MPS = 1e-6
# Where the names of the marked heights sit relative to their points (offset points), in height order.
LOCUS_LABEL_OFFSETS = [(10, 8), (12, 2), (-95, 10), (12, -16)]
DPI = 110
# Heights spaced by a constant ratio to this relative tolerance are drawn on a log axis.
GEOMETRIC_SPACING_TOLERANCE = 1e-6
MAX_MAP_PANELS = 4
# The stability map's colour scale is linear within ±this and logarithmic beyond (1/s): a phugoid
# doubling in about 12 min is still visibly red.
SIGMA_LINEAR_PER_S = 1e-3
MISSING_COLOUR = "#b0b0b0"
MAX_OPEN_LOOP_LINES = 12
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
    figures = []
    for archive in archives:
        if not (archive.has("results/modes/stability_margin_per_s") and "height_m" in archive.design_names
                and "speed_mps" in archive.design_names):
            continue
        height = archive.param("height_m")
        speed = archive.param("speed_mps")
        sigma = archive.column("results/modes/stability_margin_per_s")
        boundary = archive.boundary()
        b = archive.aircraft.wingspan_m
        for number, (key, rows) in enumerate(archive.groups(("height_m", "speed_mps"))[:MAX_MAP_PANELS]):
            rows = rows[archive.ok[rows]]
            heights, speeds = np.unique(height[rows]), np.unique(speed[rows])
            if len(heights) < 2 or len(speeds) < 2:
                continue
            grid = np.full((len(heights), len(speeds)), np.nan)
            grid[np.searchsorted(heights, height[rows]), np.searchsorted(speeds, speed[rows])] = sigma[rows]
            low, high = np.nanmin(grid), np.nanmax(grid)
            extent = max(abs(low), abs(high), 1e-12)
            # Symmetric about σ = 0 (white), logarithmic beyond SIGMA_LINEAR_PER_S so that the small
            # margins near the boundary are as visible as the large ones near the ground.
            linear = min(SIGMA_LINEAR_PER_S, extent / 10)
            norm = SymLogNorm(linthresh=linear, linscale=0.6, vmin=-extent, vmax=extent, base=10)
            fig, ax = plt.subplots(figsize=(8.6, 5.4), layout="constrained")
            colours = plt.get_cmap("RdBu_r").copy()
            colours.set_bad(MISSING_COLOUR)  # a run not complete (or failed): not white, which is σ = 0
            mesh = ax.pcolormesh(speeds, heights, np.ma.masked_invalid(grid), cmap=colours, norm=norm,
                                 shading="nearest", rasterized=True)
            bar = fig.colorbar(mesh, ax=ax, pad=0.02)
            bar.set_label("stability margin σ (1/s): red unstable (σ > 0), blue stable")
            handles = []
            if low < 0 < high:
                ax.contour(speeds, heights, grid, levels=[0.0], colors="k", linewidths=2.4)
                handles.append(Line2D([], [], color="k", lw=2.4, label="σ = 0 on the grid"))
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
            # The curve H*(u0) traced by continuation (gesweep boundary --archive, issue 16), when the
            # map's only other axis is speed.
            if "analysis/boundary_curve" in archive.file and len(key) == 0:
                traced = archive.file["analysis/boundary_curve"]
                branches = traced["branch"][...]
                for index, branch in enumerate(np.unique(branches)):
                    on = branches == branch
                    ax.plot(traced["speed_mps"][...][on], traced["height_m"][...][on], color="#ff00c8", lw=1.4,
                            label="_")
                if len(branches):
                    handles.append(Line2D([], [], color="#ff00c8", lw=1.4,
                                          label="H*(u0) traced by continuation (/analysis/boundary_curve)"))
            if b > 0:
                ax.axhline(0.5 * b, color="#00a000", ls="--", lw=1.4)
                handles.append(Line2D([], [], color="#00a000", ls="--", lw=1.4,
                                      label=f"H/b = 0.5 (H = {0.5 * b:.4g} m): the paper's boundary"))
            wheel = archive.aircraft.wheel_contact_height_m
            if wheel > 0 and heights[0] <= wheel <= heights[-1]:
                ax.axhline(wheel, color="saddlebrown", lw=1.2)
                handles.append(Line2D([], [], color="saddlebrown", lw=1.2, label=f"wheel contact ({wheel:.3g} m)"))
            if _geometric(heights):
                ax.set_yscale("log")
                ticks = [t for t in (0.8, 1, 1.5, 2, 3, 4, 5, 7, 10, 14, 20, 30, 50) if heights[0] <= t <= heights[-1]]
                ax.set_yticks(ticks)
                ax.set_yticklabels([f"{t:g}" for t in ticks])
                ax.minorticks_off()
            ax.set_xlim(speeds[0], speeds[-1])
            ax.set_ylim(heights[0], heights[-1])
            _span_axis(ax, b)
            ax.set_xlabel("reference speed u0 (m/s)")
            ax.set_ylabel("height H of the mean chord above ground (m)")
            suffix = f" ({_h_derivatives_label(archive, key)})" if key else ""
            ax.set_title(f"{archive.aircraft.name or 'aircraft'}: stability margin over height and speed{suffix}")
            ax.legend(handles=handles, loc="upper right", framealpha=0.9)
            name = _save(fig, outdir, f"stability_map_{_slug(archive.study_name)}_{number}.png")
            figures.append(Figure(name, f"Stability map ({archive.study_name}){suffix}",
                                  f"σ, the largest real part of the eigenvalues of Eq. (1) (the neutral height root left "
                                  f"out), over {len(speeds)} speeds × {len(heights)} heights ({len(rows)} runs of "
                                  f"{os.path.basename(archive.path)}). Colours are centred on σ = 0 (white); grey cells have no "
                                  f"complete ok run. The black "
                                  f"line is σ = 0 on the grid; the yellow curve, where present, is the boundary H* "
                                  f"refined on the continuous model by gesweep boundary --archive."))
    return figures


def _locus_groups(archives):
    """Every group of runs along height with the modes: (archive, key, rows sorted by height, speed,
    h-derivatives on)."""
    groups = []
    for archive in archives:
        if not (archive.has("results/modes/short_period/eigenvalue_re_per_s") and "height_m" in archive.design_names):
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
    """The group for the root locus: h-derivatives on, speed within LOCUS_SPEED_WINDOW_MPS of the
    paper's, most heights, then nearest speed."""
    best = None
    for group in groups:
        archive, key, rows, speed, on = group
        distinct = len(np.unique(archive.param("height_m")[rows]))
        if distinct < 5:
            continue
        score = (0 if on else 1, abs(speed - PAPER_SPEED_MPS) > LOCUS_SPEED_WINDOW_MPS, -distinct,
                 abs(speed - PAPER_SPEED_MPS))
        if best is None or score < best[0]:
            best = (score, group)
    return None if best is None else best[1]


def root_locus(archives, outdir):
    groups = _locus_groups(archives)
    source = _locus_source(groups)
    if source is None:
        return []
    archive, key, rows, speed, on = source
    height = archive.param("height_m")[rows]
    modes = {m: (archive.column(f"results/modes/{m}/eigenvalue_re_per_s")[rows],
                 archive.column(f"results/modes/{m}/eigenvalue_im_per_s")[rows]) for m in ("short_period", "phugoid", "height")}
    # The paper's own points: runs at exactly its speed at a few heights (the Table A2 study), if any.
    table_points = None
    for other in groups:
        if (other is not source and other[4] == on and abs(other[3] - speed) < SAME_SPEED_MPS
                and abs(other[3] - PAPER_SPEED_MPS) < SAME_SPEED_MPS and len(other[2]) <= 30):
            a, _, r, _, _ = other
            table_points = (a.param("height_m")[r], {m: (a.column(f"results/modes/{m}/eigenvalue_re_per_s")[r],
                                                         a.column(f"results/modes/{m}/eigenvalue_im_per_s")[r])
                                                     for m in modes}, a.study_name)
            break
    b = archive.aircraft.wingspan_m
    norm = LogNorm(height.min(), height.max()) if height.min() > 0 else Normalize(height.min(), height.max())
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.9), layout="constrained",
                             gridspec_kw={"width_ratios": [1, 1, 0.9]})
    # Heights named along the locus: the lowest, H/b = 0.5, H/b = 1 and the highest.
    marks = sorted({0, len(height) - 1} | {int(np.argmin(np.abs(height - r * b))) for r in (0.5, 1.0)
                                            if b > 0 and height.min() <= r * b <= height.max()})
    scatter = None
    for ax, mode, title in ((axes[0], "short_period", "short-period mode"), (axes[1], "phugoid", "phugoid mode")):
        re, im = modes[mode]
        ax.plot(re, im, color="0.55", lw=0.8, zorder=1)
        scatter = ax.scatter(re, im, c=height, cmap="viridis", norm=norm, s=16, zorder=2, edgecolors="none")
        for n, i in enumerate(marks):
            text = f"{height[i]:.3g} m" + (f" (H/b {height[i] / b:.2f})" if b > 0 else "")
            offset = LOCUS_LABEL_OFFSETS[n] if len(marks) == len(LOCUS_LABEL_OFFSETS) else (10, 8 - 14 * (n % 2))
            ax.annotate(text, (re[i], im[i]), textcoords="offset points", xytext=offset, fontsize=8,
                        arrowprops=dict(arrowstyle="-", color="0.4", lw=0.6))
        ax.scatter(re[-1:], im[-1:], marker="*", s=140, color="k", zorder=3)
        ax.scatter(re[:1], im[:1], marker="X", s=80, color="#c00000", zorder=3)
        if table_points is not None:
            tre, tim = table_points[1][mode]
            ax.scatter(tre, tim, marker="o", s=46, facecolors="none", edgecolors="k", lw=1.0, zorder=4)
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
                              label=f"Table A2 heights at {PAPER_SPEED_MPS} m/s ({table_points[2]})"))
    axes[2].legend(handles=handles, loc="lower right", fontsize=7.5)
    bar = fig.colorbar(scatter, ax=axes, pad=0.01, aspect=30)
    bar.set_label("height H (m)")
    others = {k: v for k, v in key.items() if k != "speed_mps"}
    condition = f"u0 = {speed:.6g} m/s, " + ("with" if on else "without") + " h-derivatives"
    if any(k != "h_derivatives" for k in others):
        condition += ", " + archive.key_text({k: v for k, v in others.items() if k != "h_derivatives"})
    fig.suptitle(f"Root locus as height falls from {height[-1]:.3g} m to {height[0]:.3g} m ({condition})")
    name = _save(fig, outdir, "root_locus.png")
    top_note = ""
    if archive.aircraft.table_heights_m and height[-1] >= archive.aircraft.table_heights_m[-1]:
        top_note = (f" At and above the last table row ({archive.aircraft.table_heights_m[-1]:g} m) the coefficients "
                    f"are the free-flight row, so the star is the free-flight end of the locus.")
    return [Figure(name, "Root locus against height",
                   f"Eigenvalues of Eq. (1) at {len(height)} heights of {os.path.basename(archive.path)} "
                   f"(study {archive.study_name}), coloured by height (conjugates omitted). The red cross marks the "
                   f"lowest height, the star the highest.{top_note}")]


def open_loop(archives, outdir):
    figures = []
    for archive in archives:
        if not archive.has("series/open_loop/height_m"):
            continue
        height0 = archive.param("height_m")
        rows = np.nonzero(archive.complete)[0]
        rows = rows[np.argsort(height0[rows], kind="stable")]
        if len(rows) == 0:
            continue
        if len(rows) > MAX_OPEN_LOOP_LINES:
            rows = rows[np.linspace(0, len(rows) - 1, MAX_OPEN_LOOP_LINES).round().astype(int)]
        time = archive.file["series/open_loop/time_s"][...]
        series = archive.series("series/open_loop/height_m", rows)
        groups = {int(r): key for key, members in archive.groups(("height_m",)) for r in members}
        b = archive.aircraft.wingspan_m
        wheel = archive.aircraft.wheel_contact_height_m
        speed = archive.param("speed_mps")
        amplitude = archive.param("pulse_amplitude_deg")
        duration = archive.param("pulse_duration_s")
        fig, (left, right, legend_axis) = plt.subplots(1, 3, figsize=(13, 4.9), layout="constrained",
                                                       gridspec_kw={"width_ratios": [1.6, 1, 0.62]})
        axes = (left, right)
        colors = plt.cm.viridis(np.linspace(0, 0.92, len(rows)))
        for ax, t_max in ((axes[0], time[-1]), (axes[1], min(10.0, time[-1]))):
            for color, row, h in zip(colors, rows, series):
                label = f"H0 = {height0[row]:.5g} m"
                if b > 0:
                    label += f" (H/b {height0[row] / b:.2f})"
                extra = _h_derivatives_label(archive, groups.get(int(row), {}))
                if extra:
                    label += ", " + extra
                ax.plot(time, h, color=color, lw=1.3, label=label)
                finite = np.nonzero(np.isfinite(h))[0]
                if len(finite) and finite[-1] < len(h) - 1:
                    ax.plot(time[finite[-1]], h[finite[-1]], "x", color=color, ms=7, mew=1.6)
            if wheel > 0:
                ax.axhline(wheel, color="saddlebrown", lw=1.4)
            if b > 0:
                ax.axhline(0.5 * b, color="#00a000", ls="--", lw=1.1)
            ax.set_xlim(0, t_max)
            ax.set_ylim(0, max(np.nanmax(series), np.nanmax(height0[rows])) * 1.05)
            ax.set_xlabel("time t (s)")
            ax.set_ylabel("height H (m)")
            ax.grid(alpha=0.3)
        _span_axis(axes[1], b)
        axes[0].set_title("whole run")
        axes[1].set_title("first 10 s")
        handles, labels = axes[0].get_legend_handles_labels()
        handles += [Line2D([], [], color="saddlebrown", lw=1.4), Line2D([], [], color="#00a000", ls="--"),
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
                              f"paper_fig4_open_loop). A cross ends a run before the time limit."))
    return figures


def landing(archives, outdir):
    figures = []
    for archive in archives:
        if not archive.has("series/landing/height_m"):
            continue
        rows = np.nonzero(archive.complete)[0][:MAX_LANDING_LINES]
        if len(rows) == 0:
            continue
        time = archive.file["series/landing/time_s"][...]
        data = {name: archive.series("series/landing/" + name, rows)
                for name in ("height_m", "distance_past_transmitter_m", "elevator_rad", "pitch_rate_radps")}
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
                ax.axhline(wheel, color="saddlebrown", lw=1.2)
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
