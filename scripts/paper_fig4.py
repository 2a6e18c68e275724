#!/usr/bin/python3
"""The paper's Fig. 4 from Python, notebook style (each "# %%" is a cell; docs/python.md).

The open-loop height response of the ANCE to a +5 deg elevator pulse of 0.2 s at u0 = 32.0208 m/s
from the ten start heights of Table A2, RK4 at the paper's 0.015 s for 300 s, the derivatives
re-evaluated at the current height and speed (docs/simulation.md, "The paper's experiment (Fig. 4)";
studies/paper/fig4_open_loop.toml is the same experiment as a sweep).

    PYTHONPATH=build/python /usr/bin/python3 scripts/paper_fig4.py [results/paper_fig4_python.png]

./scripts/demo runs it.
"""
# %% The module and the aircraft
import pathlib
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

import gesweep

root = pathlib.Path(__file__).resolve().parents[1]
out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else root / "results" / "paper_fig4_python.png"
ance = gesweep.Aircraft.load(root / "studies" / "aircraft" / "ance.toml")
table = ance.table
# The ten finite rows of Table A2 above the wheel-contact row (the paper's captions).
starts = [h for h in table["height_m"] if h != float("inf")][-10:]

# %% Ten open-loop responses (each a few milliseconds)
SPEED = 32.0208
responses = {
    h: gesweep.simulate(ance, h, SPEED, pulse_amplitude_deg=5.0, pulse_duration_s=0.2, integrator="rk4",
                        step_s=0.015, duration_s=300.0, output_dt_s=0.03)
    for h in starts
}
boundary = gesweep.boundary(ance, SPEED)["height_m"]

# %% The outcomes, as docs/simulation.md tabulates them
print(f"{'H0 (m)':>8} {'end event':>11} {'end (s)':>9} {'min H (m)':>10}")
for h, r in responses.items():
    s = r.summary
    print(f"{h:8.4f} {s['end_event']:>11} {s['end_time_s']:9.3f} {s['min_height_m']:10.4f}")

# %% Fig. 4: height against time, one panel per start height
fig, axes = plt.subplots(2, 5, figsize=(16, 6))
for ax, (h, r) in zip(axes.ravel(), responses.items()):
    series = r.series
    ax.plot(series["time_s"], series["height_m"], lw=0.8)
    ax.axhline(ance.wheel_contact_height_m, color="k", lw=0.6, ls=":")
    ax.axhline(boundary, color="tab:red", lw=0.6, ls="--")
    ax.set_title(f"H0 = {h:g} m ({r.summary['end_event']})", fontsize=9)
    ax.set_xlim(0, max(r.summary["end_time_s"], 2.0))  # the first dives end within 2 s
for ax in axes[1]:
    ax.set_xlabel("time_s")
for ax in axes[:, 0]:
    ax.set_ylabel("height_m")
fig.suptitle(f"{ance.name}: +5 deg elevator pulse of 0.2 s at u0 = {SPEED} m/s, RK4 0.015 s "
             f"(dotted: wheel contact; dashed: H* = {boundary:.4f} m)")
fig.tight_layout()
out.parent.mkdir(parents=True, exist_ok=True)
fig.savefig(out, dpi=110)
print(f"figure: {out}")
