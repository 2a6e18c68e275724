"""The landing-risk figures of the dispersion section, from the subset-simulation archives of `gesweep
risk` (docs/dispersion.md, "Landing risk by subset simulation"):
- per cell, the exceedance curve P(X > x) (P(X < x) for a lower limit) of each limit's column: the
  plain ECDF of the simulation's first level (plain Monte Carlo), the subset simulation's intermediate
  thresholds and its estimate at the limit with their 95 % band, and, where another archive of the
  report has a dispersion product of the same column, that sample's ECDF and its normal, Gumbel and
  GEV tail fits (the fitted quantiles it stores);
- per cell and rare limit (P < p0), the design point: the gust history of the most likely failing
  landing and of the landing flown with the failing runs' mean noise, beside the still-air landing,
  with their heights and sink rates over the last seconds before touchdown.
Every number drawn is read from the archives; nothing is estimated here."""

import os

import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

import figures_common as common
from figures_common import Figure

# Seconds before the most likely failing landing's touchdown that the design-point figure shows.
DESIGN_WINDOW_S = 40.0
# The tail fits of a dispersion product drawn beside the subset curve, with their line styles.
FITS = (("normal", "--"), ("gumbel_max", ":"), ("gumbel_min", ":"), ("gev_max", "-."))
# Colours: the subset estimate, its first (Monte Carlo) level, the plain Monte Carlo archive.
SUBSET_COLOUR, LEVEL1_COLOUR, PLAIN_COLOUR = "tab:red", "0.45", "tab:blue"


def draw(archives, outdir):
    risks = [a for a in archives if a.is_risk]
    plain = [a for a in archives if not a.is_risk and a.dispersion() is not None]
    figures = []
    for archive in risks:
        cells = sorted({l["cell"] for l in archive.result["limits"]})
        for cell in cells:
            limits = [l for l in archive.result["limits"] if l["cell"] == cell]
            figures.append(_exceedance(archive, cell, limits, plain, outdir))
            p0 = archive.result["method"]["level_probability"]
            for limit in limits:
                if limit["probability"] is not None and 0 < limit["probability"] < p0:
                    series = archive.design_series(limit)
                    if "most_likely" in series:
                        figures.append(_design_point(archive, cell, limit, series, outdir))
    return figures


def _cell_text(limits):
    label = limits[0].get("cell_label", "")
    return label or "one cell"


def _plain_curves(plain, column):
    """(label, sorted values, fits) of every dispersion product (group) of a column named `column`; fits
    maps a law's name to its stored parameters (scipy's names and signs, schemas/archive.md)."""
    out = []
    for archive in plain:
        product = archive.dispersion()
        names = [c.rsplit("/", 1)[-1] for c in product["column_paths"]]
        if column not in names:
            continue
        c = names.index(column)
        stored = product["datasets"]
        for g, label in enumerate(product["labels"]):
            values = archive.column(product["column_paths"][c])[product["members"](g)]
            values = np.sort(values[np.isfinite(values)])
            fits = {}
            for fit in ("normal", "gumbel_max", "gumbel_min", "gev_max"):
                keys = [f"{fit}_location", f"{fit}_scale"] + ([f"{fit}_shape"] if fit.startswith("gev") else [])
                if all(k in stored for k in keys):
                    fits[fit] = [float(stored[k][g, c]) for k in keys]
            out.append((f"{archive.study_name} ({label}, {values.size} runs)", values, fits))
    return out


def _fit_tail(fit, parameters, x, above):
    """P(X > x) (above) or P(X < x) of a stored fit, or None when it has no such tail or no parameters."""
    if not all(np.isfinite(parameters)):
        return None
    if fit == "normal":
        law = stats.norm(*parameters)
    elif fit == "gumbel_max" and above:
        law = stats.gumbel_r(*parameters)
    elif fit == "gumbel_min" and not above:
        law = stats.gumbel_l(*parameters)
    elif fit == "gev_max" and above:
        location, scale, shape = parameters
        law = stats.genextreme(-shape, location, scale)  # scipy's c = -xi
    else:
        return None
    return law.sf(x) if above else law.cdf(x)


def _exceedance(archive, cell, limits, plain, outdir):
    columns = []
    for limit in limits:
        if limit["column"] not in columns:
            columns.append(limit["column"])
    fig, axes = plt.subplots(1, len(columns), figsize=(common.PAGE_WIDTH_IN, 4.4), layout="constrained",
                             squeeze=False)
    floor = 1.0
    for ax, column in zip(axes[0], columns):
        mine = [l for l in limits if l["column"] == column]
        above = mine[0]["above"]
        # The first level is plain Monte Carlo: its ECDF (every limit's first level is an independent
        # sample; the first limit's is drawn).
        first = archive.rows(mine[0], level=1)
        x = np.sort(archive.values[first, archive.column(column)])
        x = x[np.isfinite(x)]
        n = x.size
        exceed = (np.arange(n, 0, -1) - 1) / n if above else np.arange(1, n + 1) / n
        keep = exceed > 0
        ax.step(x[keep], exceed[keep], where="post", color=LEVEL1_COLOUR, lw=1.2,
                label=f"level 1: plain Monte Carlo ({n} landings)")
        for label, values, fits in _plain_curves(plain, column):
            m = values.size
            p = (np.arange(m, 0, -1) - 1) / m if above else np.arange(1, m + 1) / m
            ax.step(values[p > 0], p[p > 0], where="post", color=PLAIN_COLOUR, lw=1.2, label=f"plain MC: {label}")
            # The fits are drawn from the sample's range out to the furthest limit.
            furthest = max(l["value"] for l in mine) if above else min(l["value"] for l in mine)
            grid = np.linspace(values[0], max(values[-1], furthest), 400) if above else \
                np.linspace(min(values[0], furthest), values[-1], 400)
            for fit, style in FITS:
                tail = _fit_tail(fit, fits[fit], grid, above) if fit in fits else None
                if tail is not None:
                    shown = tail > 1e-12
                    ax.plot(grid[shown], tail[shown], ls=style, color=PLAIN_COLOUR, lw=1,
                            label=f"its {fit.split('_')[0]} fit")
        for k, limit in enumerate(mine):
            curve = limit["exceedance"]
            values = [pt["value"] for pt in curve]
            p = np.array([pt["probability"] for pt in curve])
            low = np.array([pt["interval_95"][0] for pt in curve])
            high = np.array([pt["interval_95"][1] for pt in curve])
            ax.fill_between(values, low, high, color=SUBSET_COLOUR, alpha=0.15, lw=0)
            ax.plot(values, p, marker="o", ms=4, color=SUBSET_COLOUR,
                    label="subset simulation, 95 % band" if k == 0 else None)
            if limit["status"] == "level_cap" and limit["upper_bound"] is not None:
                ax.plot([limit["value"]], [limit["upper_bound"]], marker="v", ms=8, color=SUBSET_COLOUR)
            ax.axvline(limit["value"], color="0.6", lw=0.8, ls="--")
            ax.annotate(f"P = {limit['probability']:.2g}\nCoV {limit['coefficient_of_variation']:.2f}"
                        if limit["probability"] else f"P < {limit['upper_bound']:.2g}",
                        (limit["value"], max(p[-1] if p.size else 1, 1e-12)), textcoords="offset points",
                        xytext=(4, 6), fontsize=8, color=SUBSET_COLOUR)
            finite = low[low > 0]
            if finite.size:
                floor = min(floor, finite.min())
        units = mine[0].get("units", "")
        short = column.removeprefix("touchdown_")
        ax.set_xlabel(f"touchdown {short} ({units})" if units else column)
        ax.set_ylabel("P(X > x)" if above else "P(X < x)")
        ax.set_yscale("log")
        ax.grid(alpha=0.3, which="major")
        ax.legend(fontsize=7, loc="lower left" if above else "lower right")
    for ax in axes[0]:
        ax.set_ylim(10 ** np.floor(np.log10(min(floor, 1e-6)) - 0.5), 1.5)
    name = common.save(fig, outdir, f"dispersion_{common.slug(archive.study_name)}_cell{cell}_exceedance.png")
    return Figure(name, f"Exceedance curves by subset simulation ({archive.study_name}, {_cell_text(limits)})",
                  f"From {os.path.basename(archive.path)}: each limit's intermediate thresholds and estimate at the "
                  f"limit (dashed line) with the 95 % band of the lognormal interval; grey, the ECDF of the "
                  f"simulation's first level (plain Monte Carlo); blue, where the report has a Monte Carlo archive "
                  f"of the same column, its ECDF and its tail fits (docs/dispersion.md).")


def _design_point(archive, cell, limit, series, outdir):
    likely, mean, steady = series["most_likely"], series.get("mean_failure"), series.get("steady")
    t = likely["time_s"]
    touchdown = t[np.flatnonzero(np.isfinite(likely["height_m"]))[-1]]
    window = (t >= touchdown - DESIGN_WINDOW_S) & (t <= touchdown + 1)
    fig, axes = plt.subplots(3, 1, figsize=(common.PAGE_WIDTH_IN, 7.2), layout="constrained", sharex=True)
    runs = [("most likely failing landing", likely, SUBSET_COLOUR, "-"),
            ("landing in the failing runs' mean noise", mean, "tab:orange", "-"),
            ("still-air landing (u = 0)", steady, "0.2", "--")]
    for label, s, colour, style in runs:
        if s is None:
            continue
        w = (s["time_s"] >= touchdown - DESIGN_WINDOW_S) & (s["time_s"] <= touchdown + 1)
        axes[0].plot(s["time_s"][w], s["w_g_mps"][w], color=colour, ls=style, lw=1, label=label)
        axes[1].plot(s["time_s"][w], s["height_m"][w], color=colour, ls=style, lw=1)
        axes[2].plot(s["time_s"][w], s["sink_rate_mps"][w], color=colour, ls=style, lw=1)
    axes[0].set_ylabel("vertical gust w_g (m/s)")
    axes[1].set_ylabel("height (m)")
    axes[2].set_ylabel("sink rate (m/s)")
    axes[2].set_xlabel("time (s)")
    if limit["column"] == "touchdown_sink_rate_mps":
        axes[2].axhline(limit["value"], color="0.6", lw=0.8, ls="--")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    design = limit["design_point"]
    name = common.save(fig, outdir, f"dispersion_{common.slug(archive.study_name)}_cell{cell}_"
                                    f"{common.slug(limit['limit'])}_design_point.png")
    return Figure(name, f"Design point of {limit['limit']} ({archive.study_name}, {_cell_text([limit])})",
                  f"The last {DESIGN_WINDOW_S:g} s before touchdown. Red: the failing landing of the last level "
                  f"nearest the origin of the noise space (|u| = {design.get('most_likely_distance', float('nan')):.1f}, "
                  f"{limit['column']} = {design.get('most_likely_value', float('nan')):.3g}); orange: the landing "
                  f"flown with the mean noise of the {design.get('failing_runs_last_level', 0)} failing runs of the "
                  f"last level; dashed: the landing without turbulence (mean wind and shear only).")
