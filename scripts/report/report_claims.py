"""The paper's claims beside the engine's findings (docs/report.md, "Paper and engine").

The paper's side is quoted from the seed paper (Section IV and Fig. 4-9). The engine's side is read
from the archives given to the report and nothing else: a claim whose data are absent is listed as
"no archive holds ...". Each claim reads the archives it is about, and only those: the modes at the
paper's speed, the open-loop runs at the paper's Fig. 4 condition outside turbulence, the paper's
landing study (by its study name). Dispersion archives appear only in their own section. Each row is
a Claim: its engine side a few lines at most, the per-run evidence behind it in `details` (shown
collapsed).
"""

import math
import os
import sys
from dataclasses import dataclass, field

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
LANDING_SINK_RATE = columns.path("landing", "touchdown_sink_rate_mps")
LANDING_DISTANCE = columns.path("landing", "touchdown_distance_past_transmitter_m")
# The paper's landing study (studies/paper/landing.toml): the landing claim is about its archive only.
PAPER_LANDING_STUDY = "paper_landing"

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


@dataclass
class Claim:
    claim: str     # what the paper claims, in a line
    paper: str     # the paper's own result
    engine: str    # the engine's, from the archives: a few lines at most
    verdict: str   # "agrees", "differs...", or "no data"
    details: list = field(default_factory=list)  # one line per run behind `engine`, shown collapsed
    sources: list = field(default_factory=list)  # the archives read (file names)


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
    pairs, b, sources = set(), math.nan, []
    for archive in archives:
        if not (archive.has(SIGMA) and archive.aircraft.name == "ANCE"):
            continue
        rows = _h_on(archive, _speed_rows(archive, np.nonzero(archive.ok)[0]))
        height = archive.param("height_m")
        if len(rows) == 0 or height is None:
            continue
        table = np.asarray(archive.aircraft.table_heights_m)
        at_table = [r for r in rows if len(table) and np.min(np.abs(table - height[r])) < HEIGHT_MATCH_M]
        if not at_table:
            continue
        sigma = archive.column(SIGMA)
        pairs |= {(float(height[r]), float(sigma[r])) for r in at_table}
        b = archive.aircraft.wingspan_m
        sources.append(os.path.basename(archive.path))
    boundary_text, boundary_ratio, boundary_source = _boundary_at_paper_speed(archives)
    if boundary_source:
        sources.append(boundary_source)
    if not pairs:
        engine = "no archive holds the modes at the Table A2 heights at 32.0208 m/s with h-derivatives"
        return Claim(claim, paper, engine + ("; " + boundary_text if boundary_text else ""), "no data", [], sources)
    pairs = sorted(pairs)
    stable = [h for h, s in pairs if s < 0]
    unstable = [h for h, s in pairs if s >= 0]
    engine = (f"at the {len(pairs)} Table A2 heights: stable (σ < 0) at H = {_fmt_heights(stable) or 'none'} m; "
              f"unstable (σ ≥ 0) at H = {_fmt_heights(unstable) or 'none'} m")
    if boundary_text:
        engine += "; " + boundary_text
    details = [f"H = {h:.5g} m (H/b = {h / b:.3f}): σ = {s:+.3e} 1/s" for h, s in pairs]
    limit = 0.5 * b
    wrong = [(h, s) for h, s in pairs if (h >= limit - HEIGHT_MATCH_M) != (s < 0)]
    if not wrong:
        return Claim(claim, paper, engine, "agrees", details, sources)
    verdict = "differs: " + "; ".join(f"at H/b = {h / b:.3f} σ = {s:+.3g} 1/s ({'stable' if s < 0 else 'unstable'})"
                                      for h, s in wrong)
    if boundary_ratio is not None:
        verdict += f"; the continuous boundary is at H*/b = {boundary_ratio:.3f}"
    return Claim(claim, paper, engine, verdict, details, sources)


def _boundary_at_paper_speed(archives):
    """H* at 32.0208 m/s with h-derivatives from any /analysis/boundary: a point at exactly that speed
    first (a swept or a fixed speed), else interpolated in speed between two refined points."""
    interpolated = ("", None, "")
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
                    f"({archive.study_name})", h / b, os.path.basename(archive.path))
        if not interpolated[0] and len(speed) >= 2 and speed[0] < PAPER_SPEED_MPS < speed[-1]:
            i = int(np.searchsorted(speed, PAPER_SPEED_MPS))
            if np.isfinite(height[i - 1]) and np.isfinite(height[i]):
                w = (PAPER_SPEED_MPS - speed[i - 1]) / (speed[i] - speed[i - 1])
                h = float(height[i - 1] + w * (height[i] - height[i - 1]))
                interpolated = (f"boundary H* ≈ {h:.5g} m (H*/b ≈ {h / b:.4f}), interpolated between the refined "
                                f"boundaries at {speed[i - 1]:.5g} and {speed[i]:.5g} m/s ({archive.study_name})",
                                h / b, os.path.basename(archive.path))
    return interpolated


def _open_loop_runs(archives):
    """(archive, row, start height) of every complete open-loop run at the paper's condition (u0, the
    +5°, 0.2 s pulse, h-derivatives on), outside the dispersion studies."""
    runs = []
    for archive in archives:
        if not (archive.has(OPEN_LOOP_END_EVENT) and archive.aircraft.name == "ANCE") or archive.is_dispersion():
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


def _sources(runs):
    return sorted({os.path.basename(a.path) for a, _, _ in runs})


def _fig4_no_data(claim, paper, what="the Fig. 4 open-loop runs"):
    return Claim(claim, paper, f"no archive holds {what} (32.0208 m/s, +5° for 0.2 s, h-derivatives)", "no data")


def fig4_claims(archives):
    runs = sorted(_open_loop_runs(archives), key=lambda run: run[2])
    rows = []
    claim = "Starting at or below 2.5935 m, the airplane sinks to the ground"
    paper = "touchdown for every start height ≤ 2.5935 m"
    low = [(a, r, h) for a, r, h in runs if h <= FIG4_TOUCHDOWN_MAX_M + HEIGHT_MATCH_M]
    if not low:
        rows.append(_fig4_no_data(claim, paper))
    else:
        touched = [(a, r, h) for a, r, h in low if _event(a, r) == "touchdown"]
        engine = f"{len(touched)} of the {len(low)} runs from {_fmt_heights(h for _, _, h in low)} m touch down"
        if touched:
            ends = [a.column(OPEN_LOOP_END_TIME)[r] for a, r, _ in touched]
            engine += f", after {min(ends):.3g} to {max(ends):.3g} s"
        details = [f"{h:.5g} m: {_event_text(a, r)}" for a, r, h in low]
        rows.append(Claim(claim, paper, engine, "agrees" if len(touched) == len(low) else "differs", details,
                          _sources(low)))

    # "Convergent and damped": the run stays airborne, and the modes at its start height are all
    # damped (σ < 0, from the modes analysis of the same run when the study ran it).
    claim = "Starting at 5.5922 m and above, the response converges"
    paper = "convergent, damped response for every start height ≥ 5.5922 m"
    high = [(a, r, h) for a, r, h in runs if h >= FIG4_CONVERGE_MIN_M - HEIGHT_MATCH_M]
    if not high:
        rows.append(_fig4_no_data(claim, paper))
    else:
        details, converged = [], 0
        for a, r, h in high:
            sigma = _margin(a, r)
            ok = _event(a, r) == "time_limit" and (sigma is None or sigma < 0)
            converged += ok
            text = f"{h:.5g} m: {_event_text(a, r)}"
            if sigma is not None:
                text += f", σ = {sigma:+.2e} 1/s at the start height ({'damped' if sigma < 0 else 'not damped'})"
            details.append(text)
        engine = (f"{converged} of the {len(high)} runs from {_fmt_heights(h for _, _, h in high)} m stay airborne "
                  f"to the end with every mode damped (σ < 0) at the start height")
        rows.append(Claim(claim, paper, engine, "agrees" if converged == len(high) else "differs", details,
                          _sources(high)))

    claim = "Starting at 2.9987 m, the airplane sinks to 2.4912 m, then diverges until stall"
    paper = "lowest height 2.4912 m, then a divergent response until the stall speed"
    mid = [(a, r, h) for a, r, h in runs if abs(h - FIG4_DIVERGE_START_M) < HEIGHT_MATCH_M]
    if not mid:
        rows.append(_fig4_no_data(claim, paper, "the 2.9987 m open-loop run"))
    else:
        a, r, _ = mid[0]
        dip = a.column(OPEN_LOOP_MIN_HEIGHT)[r]
        dip_time = a.column(OPEN_LOOP_MIN_HEIGHT_TIME)[r]
        engine = f"lowest height {dip:.4g} m at {dip_time:.3g} s; {_event_text(a, r)}"
        ok = abs(dip - FIG4_DIVERGE_DIP_M) <= FIG4_DIP_AGREEMENT_M and _event(a, r) in ("stall", "diverged")
        rows.append(Claim(claim, paper, engine, "agrees" if ok else "differs", [], _sources(mid[:1])))
    return rows


def _landing_line(archive, row):
    """What one landing did, in a line: "landed at 225.51 s, sink rate 0.2035 m/s, 314.9 m past ..."."""
    outcome = archive.column(LANDING_OUTCOME)[row]
    name = "failed" if math.isnan(outcome) else archive.levels(LANDING_OUTCOME)[int(outcome)]
    if name != "landed":
        return name
    touchdown = archive.column(LANDING_TOUCHDOWN_TIME)[row]
    sink, distance = archive.column(LANDING_SINK_RATE)[row], archive.column(LANDING_DISTANCE)[row]
    return f"landed at {touchdown:.5g} s, sink rate {sink:.4g} m/s, {distance:.4g} m past the transmitter"


def landing_claim(archives):
    """The paper's landing (study PAPER_LANDING_STUDY): what each plant did, one line each."""
    claim = "The controlled airplane reaches the runway only when the h-derivatives are in the model"
    paper = "with h-derivatives: touchdown; without: no touchdown"
    outcomes, sources = {}, []
    for archive in archives:
        if not (archive.study_name == PAPER_LANDING_STUDY and archive.has(LANDING_OUTCOME)):
            continue
        sources.append(os.path.basename(archive.path))
        h = archive.param("h_derivatives")
        for r in np.nonzero(archive.complete)[0]:
            on = True if h is None else bool(h[r] == 1)
            outcomes.setdefault(on, []).append(_landing_line(archive, r))
    if True not in outcomes or False not in outcomes:
        return Claim(claim, paper, f"no archive of the study {PAPER_LANDING_STUDY} (studies/paper/landing.toml) holds "
                                   f"its landings with and without the h-derivatives", "no data", [], sources)
    lines = [f"{'with' if on else 'without'} h-derivatives: {text}" for on in (True, False) for text in outcomes[on]]
    lands_with = all(o.startswith("landed") for o in outcomes[True])
    lands_without = any(o.startswith("landed") for o in outcomes[False])
    return Claim(claim, paper, "\n".join(lines), "agrees" if lands_with and not lands_without else "differs", [],
                 sources)


def paper_claims(archives):
    """Every Claim, or [] when no archive is of the ANCE."""
    if not any(a.aircraft.name == "ANCE" for a in archives):
        return []
    return [modes_claim(archives)] + fig4_claims(archives) + [landing_claim(archives)]
