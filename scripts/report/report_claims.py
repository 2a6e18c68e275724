"""The paper's claims beside the engine's findings (docs/report.md, "Paper and engine").

The paper's side is quoted from the seed paper (Section IV and Fig. 4-9). The engine's side is read
from the archives given to the report and nothing else: a claim whose data are absent is listed as
"no archive holds ...". Each row: (claim, paper, engine, verdict) where verdict is "agrees",
"differs" or "no data".
"""

import math
import os
import sys

import numpy as np

_LIB = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "lib")
if _LIB not in sys.path:
    sys.path.insert(0, _LIB)
import columns  # noqa: E402  (scripts/lib/columns.py: archive paths from `gesweep columns --json`)

# The columns the claims read.
SIGMA = columns.path("modes", "stability_margin_per_s")
OPEN_LOOP_END_EVENT = columns.path("open_loop", "end_event")
OPEN_LOOP_END_TIME = columns.path("open_loop", "end_time_s")
OPEN_LOOP_MIN_HEIGHT = columns.path("open_loop", "min_height_m")
OPEN_LOOP_MIN_HEIGHT_TIME = columns.path("open_loop", "min_height_time_s")
LANDING_OUTCOME = columns.path("landing", "outcome")
LANDING_TOUCHDOWN_TIME = columns.path("landing", "touchdown_time_s")

PAPER_SPEED_MPS = 32.0208
# A run is "at the paper's speed" when its speed is within this of 32.0208 m/s (the studies store it exactly).
SPEED_MATCH_MPS = 1e-6
PAPER_BOUNDARY_HEIGHT_M = 2.5935   # H/b = 0.5, Table A2
FIG4_TOUCHDOWN_MAX_M = 2.5935      # "starting heights equal to or lower than 2.5935 m ... sink to the ground"
FIG4_CONVERGE_MIN_M = 5.5922       # "for greater heights ... convergent and damped"
FIG4_DIVERGE_START_M = 2.9987      # "for 2.9987 m the aircraft sinks to 2.4912 m ... divergent ... until stall"
FIG4_DIVERGE_DIP_M = 2.4912
# The dip of the 2.9987 m run agrees with the paper's when within this (about the figure's reading accuracy).
FIG4_DIP_AGREEMENT_M = 0.05
# A start height "is" one of the paper's when within this of it (the studies use the table's values).
HEIGHT_MATCH_M = 1e-4


def _speed_rows(archive, rows):
    speed = archive.param("speed_mps")
    if speed is None:
        return rows[:0]
    return rows[np.abs(speed[rows] - PAPER_SPEED_MPS) < SPEED_MATCH_MPS]


def _h_on(archive, rows, on=True):
    h = archive.param("h_derivatives")
    if h is None:  # the default is on
        return rows if on else rows[:0]
    return rows[(h[rows] == 1) == on]


def _fmt_heights(heights):
    return ", ".join(f"{h:.5g}" for h in sorted(heights))


def modes_claim(archives):
    claim = "Stable from free flight down to H = 2.5935 m (H/b = 0.5), unstable below (u0 = 32.0208 m/s)"
    paper = "stable for H/b ≥ 0.5, unstable for H/b < 0.5 (after Boschetti and Cárdenas)"
    heights, sigmas, b, sources = [], [], math.nan, []
    for archive in archives:
        if not (archive.has(SIGMA) and archive.aircraft.name == "ANCE"):
            continue
        rows = np.nonzero(archive.ok)[0]
        rows = _h_on(archive, _speed_rows(archive, rows))
        height = archive.param("height_m")
        if len(rows) == 0 or height is None:
            continue
        table = np.asarray(archive.aircraft.table_heights_m)
        at_table = [r for r in rows if len(table) and np.min(np.abs(table - height[r])) < HEIGHT_MATCH_M]
        if not at_table:
            continue
        sigma = archive.column(SIGMA)
        heights += [float(height[r]) for r in at_table]
        sigmas += [float(sigma[r]) for r in at_table]
        b = archive.aircraft.wingspan_m
        sources.append(archive.study_name)
    boundary_text, boundary_ratio = _boundary_at_paper_speed(archives)
    if not heights:
        engine = "no archive holds the modes at the Table A2 heights at 32.0208 m/s with h-derivatives"
        if boundary_text:
            engine += "; " + boundary_text
        return (claim, paper, engine, "no data")
    pairs = sorted(set(zip(heights, sigmas)))
    stable = [h for h, s in pairs if s < 0]
    unstable = [h for h, s in pairs if s >= 0]
    engine = (f"at the Table A2 heights ({', '.join(sorted(set(sources)))}): stable (σ < 0) at H = "
              f"{_fmt_heights(stable) or 'none'} m; unstable (σ ≥ 0) at H = {_fmt_heights(unstable) or 'none'} m")
    if boundary_text:
        engine += "; " + boundary_text
    limit = 0.5 * b
    wrong = [(h, s) for h, s in pairs if (h >= limit - HEIGHT_MATCH_M) != (s < 0)]
    if not wrong:
        verdict = "agrees"
    else:
        details = "; ".join(f"at H/b = {h / b:.3f} σ = {s:+.3g} 1/s ({'stable' if s < 0 else 'unstable'})"
                            for h, s in wrong)
        verdict = "differs: " + details
        if boundary_ratio is not None:
            verdict += f"; the continuous boundary is at H*/b = {boundary_ratio:.3f}"
    return (claim, paper, engine, verdict)


def _boundary_at_paper_speed(archives):
    """H* at 32.0208 m/s with h-derivatives from any /analysis/boundary: a point at exactly that speed
    first (a swept or a fixed speed), else interpolated in speed between two refined points."""
    interpolated = ("", None)
    for archive in archives:
        boundary = archive.boundary()
        if boundary is None:
            continue
        keys = boundary["keys"]
        if any(k not in ("speed_mps", "h_derivatives") for k in keys):
            continue
        n = len(boundary["height_m"])
        if "speed_mps" in keys:
            speed = np.asarray(boundary["speed_mps"], dtype=float)
        else:
            fixed = archive.param("speed_mps")
            if fixed is None or len(fixed) == 0:
                continue
            speed = np.full(n, float(fixed[0]))
        select = np.ones(n, dtype=bool)
        h_derivatives = archive.param("h_derivatives")
        if "h_derivatives" in keys:
            select &= np.asarray(boundary["h_derivatives"]) == 1
        elif h_derivatives is not None and len(h_derivatives) and h_derivatives[0] != 1:
            continue
        speed, height = speed[select], np.asarray(boundary["height_m"], dtype=float)[select]
        order = np.argsort(speed)
        speed, height = speed[order], height[order]
        b = float(boundary["attrs"].get("wingspan_m", archive.aircraft.wingspan_m))
        exact = np.nonzero(np.abs(speed - PAPER_SPEED_MPS) < SPEED_MATCH_MPS)[0]
        if len(exact) and np.isfinite(height[exact[0]]):
            h = float(height[exact[0]])
            return (f"boundary H* = {h:.5g} m (H*/b = {h / b:.4f}) refined on the continuous model "
                    f"({archive.study_name})", h / b)
        if not interpolated[0] and len(speed) >= 2 and speed[0] < PAPER_SPEED_MPS < speed[-1]:
            i = int(np.searchsorted(speed, PAPER_SPEED_MPS))
            if np.isfinite(height[i - 1]) and np.isfinite(height[i]):
                w = (PAPER_SPEED_MPS - speed[i - 1]) / (speed[i] - speed[i - 1])
                h = float(height[i - 1] + w * (height[i] - height[i - 1]))
                interpolated = (f"boundary H* ≈ {h:.5g} m (H*/b ≈ {h / b:.4f}), interpolated between the refined "
                                f"boundaries at {speed[i - 1]:.5g} and {speed[i]:.5g} m/s ({archive.study_name})",
                                h / b)
    return interpolated


def _open_loop_runs(archives):
    """(archive, row, start height) of every complete open-loop run at the paper's condition."""
    runs = []
    for archive in archives:
        if not (archive.has(OPEN_LOOP_END_EVENT) and archive.aircraft.name == "ANCE"):
            continue
        rows = _h_on(archive, _speed_rows(archive, np.nonzero(archive.complete)[0]))
        amplitude = archive.param("pulse_amplitude_deg")
        duration = archive.param("pulse_duration_s")
        height = archive.param("height_m")
        for r in rows:
            if amplitude is not None and abs(amplitude[r] - 5.0) < 1e-9 and duration is not None \
                    and abs(duration[r] - 0.2) < 1e-9:
                runs.append((archive, int(r), float(height[r])))
    return runs


def _event(archive, row):
    value = archive.column(OPEN_LOOP_END_EVENT)[row]
    levels = archive.levels(OPEN_LOOP_END_EVENT)
    if math.isnan(value):
        return "failed"
    return levels[int(value)] if levels and 0 <= int(value) < len(levels) else str(value)


def _event_text(archive, row):
    event = _event(archive, row)
    end = archive.column(OPEN_LOOP_END_TIME)[row]
    if event == "time_limit":
        return f"airborne at the end of the run ({end:.3g} s)"
    return f"{event} at {end:.3g} s"


def _margin(archive, row):
    """σ of the run at its start height (the modes analysis of the same run), or None."""
    if not archive.has(SIGMA):
        return None
    value = archive.column(SIGMA)[row]
    return None if math.isnan(value) else float(value)


def fig4_claims(archives):
    runs = _open_loop_runs(archives)
    rows = []
    claim = "Starting at or below 2.5935 m, the airplane sinks to the ground"
    paper = "touchdown for every start height ≤ 2.5935 m"
    low = [(a, r, h) for a, r, h in runs if h <= FIG4_TOUCHDOWN_MAX_M + HEIGHT_MATCH_M]
    if not low:
        rows.append((claim, paper, "no archive holds the Fig. 4 open-loop runs", "no data"))
    else:
        details = [f"{h:.5g} m: {_event_text(a, r)}" for a, r, h in sorted(low, key=lambda x: x[2])]
        ok = all(_event(a, r) == "touchdown" for a, r, _ in low)
        rows.append((claim, paper, "; ".join(details), "agrees" if ok else "differs"))

    # "Convergent and damped": the run stays airborne, and the modes at its start height are all
    # damped (σ < 0, from the modes analysis of the same run when the study ran it).
    claim = "Starting at 5.5922 m and above, the response converges"
    paper = "convergent, damped response for every start height ≥ 5.5922 m"
    high = [(a, r, h) for a, r, h in runs if h >= FIG4_CONVERGE_MIN_M - HEIGHT_MATCH_M]
    if not high:
        rows.append((claim, paper, "no archive holds the Fig. 4 open-loop runs", "no data"))
    else:
        details, ok = [], True
        for a, r, h in sorted(high, key=lambda x: x[2]):
            sigma = _margin(a, r)
            airborne = _event(a, r) == "time_limit"
            ok = ok and airborne and (sigma is None or sigma < 0)
            text = f"{h:.5g} m: {_event_text(a, r)}"
            if sigma is not None:
                text += f", σ = {sigma:+.2e} 1/s at the start height ({'damped' if sigma < 0 else 'not damped'})"
            details.append(text)
        rows.append((claim, paper, "; ".join(details), "agrees" if ok else "differs"))

    claim = "Starting at 2.9987 m, the airplane sinks to 2.4912 m, then diverges until stall"
    paper = "lowest height 2.4912 m, then a divergent response until the stall speed"
    mid = [(a, r, h) for a, r, h in runs if abs(h - FIG4_DIVERGE_START_M) < HEIGHT_MATCH_M]
    if not mid:
        rows.append((claim, paper, "no archive holds the 2.9987 m open-loop run", "no data"))
    else:
        a, r, _ = mid[0]
        dip = a.column(OPEN_LOOP_MIN_HEIGHT)[r]
        dip_time = a.column(OPEN_LOOP_MIN_HEIGHT_TIME)[r]
        engine = f"lowest height {dip:.4g} m at {dip_time:.3g} s; {_event_text(a, r)}"
        ok = abs(dip - FIG4_DIVERGE_DIP_M) <= FIG4_DIP_AGREEMENT_M and _event(a, r) in ("stall", "diverged")
        rows.append((claim, paper, engine, "agrees" if ok else "differs"))
    return rows


def landing_claim(archives):
    claim = "The controlled airplane reaches the runway only when the h-derivatives are in the model"
    paper = "with h-derivatives: touchdown; without: no touchdown"
    outcomes = {}
    for archive in archives:
        if not (archive.has(LANDING_OUTCOME) and archive.aircraft.name == "ANCE"):
            continue
        outcome = archive.column(LANDING_OUTCOME)
        levels = archive.levels(LANDING_OUTCOME)
        h = archive.param("h_derivatives")
        for r in np.nonzero(archive.complete)[0]:
            on = True if h is None else bool(h[r] == 1)
            name = "failed" if math.isnan(outcome[r]) else levels[int(outcome[r])]
            touchdown = archive.column(LANDING_TOUCHDOWN_TIME)[r]
            text = name + (f" at {touchdown:.5g} s" if name == "landed" and np.isfinite(touchdown) else "")
            outcomes.setdefault(on, []).append(text)
    if True not in outcomes or False not in outcomes:
        return (claim, paper, "no archive holds landings both with and without the h-derivatives", "no data")
    engine = f"with h-derivatives: {'; '.join(outcomes[True])}; without: {'; '.join(outcomes[False])}"
    lands_with = all(o.startswith("landed") for o in outcomes[True])
    lands_without = any(o.startswith("landed") for o in outcomes[False])
    return (claim, paper, engine, "agrees" if lands_with and not lands_without else "differs")


def paper_claims(archives):
    """Every claim row, or [] when no archive is of the ANCE."""
    if not any(a.aircraft.name == "ANCE" for a in archives):
        return []
    return [modes_claim(archives)] + fig4_claims(archives) + [landing_claim(archives)]
