"""The global sensitivity bars (docs/sensitivity.md): Sobol' indices or Morris effects of one output,
from /analysis/sensitivity."""

import os

import matplotlib.pyplot as plt
import numpy as np

import figures_common as common
from figures_common import Figure


def draw(archives, outdir):
    figures = []
    for archive in archives:
        for product in archive.sensitivity_products():
            figure = _bars(archive, product, outdir)
            if figure is not None:
                figures.append(figure)
    return figures


def _bars(archive, product, outdir):
    """The bar chart of one /analysis/sensitivity result group, or None for a method it cannot draw."""
    path, attrs, data = product["path"], product["attrs"], product["datasets"]
    method = str(attrs.get("method"))
    parameters = [str(p) for p in attrs.get("parameters", [])]
    output = str(attrs.get("output", path.split("/")[-1]))
    level = float(attrs.get("confidence_level", 0.95)) * 100
    if method == "sobol" and "first_order" in data and "total" in data:
        bars = [("first_order", "first order S_i", "#1f77b4"), ("total", "total S_Ti", "#ff7f0e")]
        ylabel = "Sobol' index (1)"
        title = f"Sobol' indices of {output} (N = {attrs.get('n', '?')} base samples)"
    elif method == "morris" and "mu_star" in data:
        bars = [("mu_star", "μ* (mean |elementary effect|)", "#1f77b4"), ("sigma", "σ of the effects", "#aaaaaa")]
        ylabel = f"effect on {output} ({product['units'].get('mu_star', '')})"
        title = f"Morris elementary effects of {output} ({attrs.get('n', '?')} trajectories)"
    else:
        return None
    x = np.arange(len(parameters))
    fig, ax = plt.subplots(figsize=(min(common.PAGE_WIDTH_IN, max(6.0, 0.75 * len(parameters) + 3)), 4.4),
                           layout="constrained")
    width = 0.8 / len(bars)
    for i, (dataset, label, color) in enumerate(bars):
        if dataset not in data:
            continue
        values = data[dataset]
        error = None
        if dataset + "_ci" in data:
            ci = data[dataset + "_ci"]
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
    name = common.save(fig, outdir, f"sensitivity_{common.slug(archive.study_name)}_{common.slug(output)}.png")
    return Figure(name, f"Sensitivity of {output} ({archive.study_name})",
                  f"From {path} of {os.path.basename(archive.path)}: bars with bootstrap confidence intervals "
                  f"(docs/sensitivity.md).")
