#!/usr/bin/python3
"""`gesweep risk`: the landing risk by subset simulation, end to end (issue 27; docs/dispersion.md,
"Landing risk by subset simulation").

    /usr/bin/python3 tests/risk/risk_cli_test.py GESWEEP

The oracles are the engine's own uninterrupted, single-threaded run (an identity, not a number it
produced): what is checked is that the estimate does not depend on how it was reached.
1. Threads: the same study on 1 and on 2 threads writes the same estimate (result_json) and the same
   evaluations, bit for bit; and so at --lanes 1, 2 and 4 (its landings one at a time or in SIMD lanes).
2. Kill and resume: SIGTERM during a level (exit 143, no archive, a journal), then SIGKILL during a level
   of the resumed run; `--resume` twice finishes to the uninterrupted archive's estimate and evaluations,
   bit for bit.
3. Replay: every row of the last level of each limit, flown again from the archive alone
   (`--replay ROW --format json`), gives the stored values bit for bit.
4. `gesweep dispersion ARCHIVE --format json` has, per limit, probability, coefficient_of_variation,
   interval_95 (around the probability), runs and thresholds (increasing towards the limit), and its
   probability is the product of the levels' conditional probabilities, recounted here from the
   archive's chain states (an independent recount of the estimator's arithmetic).
5. A limit no landing reaches within the level cap is a clearly reported result: status level_cap
   and an upper bound p0^max_levels. `gesweep report` of the archive draws the exceedance curve and the
   firm limit's design point (and none for the unreachable limit).
6. Bad input: one line naming file, key, value and expectation, exit 2, nothing written.
7. Repetitions: K = 3 runs; the first is the run without repetitions (same seed, same estimate); the
   pooled P is their mean and its CoV their spread over sqrt(K), recomputed here; a landing of the last
   repetition replays bit for bit; repetitions = 0 is refused.
8. The table's COLLAPSED line follows its rule (ancestors x 10 < chains) on an archive edited by hand.
9. Random parameters (a monte_carlo design's, through their inverse CDFs): analytic oracles on the
   verification model linear = x1 beside a still-air landing, x1 ~ normal(0, 1) with P(x1 > 3) = Phi(-3)
   (the design point at beta = 3) and x1 ~ uniform(0, 1) with P(x1 > 0.999) = 1e-3, each over 10
   repetitions; a random headwind in turbulence: one coordinate after the noise's, 1 and 2 threads
   alike and last-level landings replayed bit for bit; a random start height (a longer noise) and an
   lhs design refused with one line.
10. The 1 - cos gust's amplitude and half-length as random parameters (they are run parameters of the
   catalogue like the wind): a still-air landing from 30 m with a down (w) gust entering at 17.5 s,
   just before touchdown; amplitude ~ normal(0.5, 0.5) m/s, half-length ~ uniform(20, 30) m, limit
   touchdown_sink_rate_mps > 1.5. The oracle is independent of the subset simulation: for each
   half-length the threshold amplitude a*(d) is found by bisection on deterministic `gesweep land`
   runs (the sink rate rises with the amplitude past a*, and stays below the limit from mu - 5 sigma up
   to it), and P = E_d[Phi(-(a*(d) - mu)/sigma)] by Gauss-Legendre over d; the pooled estimate of 10
   repetitions within 3 CoV of it; the most likely failing landing just past a* at its half-length and,
   flown by `gesweep land` at its parameter values, the stored row bit for bit; last-level landings
   replayed bit for bit."""
import json
import math
import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

GESWEEP = os.path.abspath(sys.argv[1])
ROOT = pathlib.Path(__file__).resolve().parents[2]
ANCE = ROOT / "studies" / "aircraft" / "ance.toml"

# A short turbulent landing (from 30 m, about 1 ms of CPU each in Release): a firm-landing limit whose
# probability is a few per cent (two levels), and an unreachable one (the level cap).
SUBSET = '''level_probability = 0.1
samples_per_level = {n}
max_levels = {levels}
seed = 7'''
STUDY = '''format_version = 1
name = "risk_test"
aircraft = "{aircraft}"
[analyses.landing]
[parameters]
height_m = 30.0
speed_mps = 52.21
wind_shear = "logarithmic"
turbulence = "{turbulence}"
wind_20ft_mps = -15.433333
[subset]
limits = [{limits}]
{subset}
'''
LIMITS = '"touchdown_sink_rate_mps > 1.83", "touchdown_sink_rate_mps > 30"'

# A monte_carlo design's parameters as random inputs (section 9): {analyses} beside the landing, the
# parameter {name} drawn as {distribution}.
RANDOM_STUDY = '''format_version = 1
name = "risk_random"
aircraft = "{aircraft}"
[analyses.landing]
{analyses}
[parameters]
{parameters}
[design]
kind = "{kind}"
samples = 1
seed = 1
[[design.parameter]]
name = "{name}"
{distribution}
{more_parameters}
[subset]
limits = [{limits}]
{subset}
'''
# Phi(-3), the standard normal's upper tail at 3 (Abramowitz & Stegun, Table 26.1: 1.349898e-3).
PHI_MINUS_3 = 1.3498980316301e-3
# A pooled estimate of 10 repetitions is within this many of its coefficients of variation of the truth
# (a deterministic run: the seed is fixed; 3 is a 0.3 % two-sided tail for a normal error).
ORACLE_SIGMAS = 3.0
# The most likely failing point of x1 > 3 is the last level's smallest failing x1: within this of 3.
DESIGN_POINT_SLACK = 0.1

# Section 10: a down 1 - cos gust meeting a still-air landing from 30 m (touchdown near 18-19 s) just
# before touchdown. Its amplitude ~ normal(GUST_MEAN_MPS, GUST_SIGMA_MPS) (mean above 0: an up gust of
# the same size makes a hard landing too, by ballooning, but only below about -3 m/s, 7 sigma away; the
# test checks the limit is not reached down to mu - 5 sigma, a tail of 3e-7 left out of the truth), its
# half-length ~ uniform(GUST_HALF_LENGTHS_M).
GUST_START_S = 17.5
GUST_MEAN_MPS, GUST_SIGMA_MPS = 0.5, 0.5
GUST_HALF_LENGTHS_M = (20.0, 30.0)
GUST_LIMIT_MPS = 1.5
# The truth's quadrature over the half-length: Gauss-Legendre nodes (8 nodes change it by 0.02 %).
GUST_NODES = 5
# The bisection stops when the bracket of a* is this narrow, m/s: P moves by beta * width / sigma,
# about 0.1 %, far inside the test's tolerance (3 CoV, about 40 %).
GUST_BISECTION_WIDTH_MPS = 2e-4
# The most likely failing landing is a failing landing of the last level nearest the origin: its
# amplitude is past a* at its half-length, by less than this, m/s (a fifth of sigma).
GUST_DESIGN_POINT_SLACK_MPS = 0.1
# One run's stated CoV and the spread measured over 10 repetitions agree within this factor (the
# measured one, from 9 degrees of freedom, is within [0.39, 1.6] of the truth 99.7 % of the time).
COV_RATIO_BOUND = 2.0

failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL:", what)


def write_study(directory, name, n=100, levels=3, limits=LIMITS, turbulence="dryden", subset=None):
    path = pathlib.Path(directory) / name
    path.write_text(STUDY.format(aircraft=ANCE, turbulence=turbulence, limits=limits,
                                 subset=subset if subset is not None else SUBSET.format(n=n, levels=levels)))
    return path


def risk(*args, **kw):
    return subprocess.run([GESWEEP, "risk", *map(str, args)], capture_output=True, text=True, **kw)


def contents(path):
    """The archive's estimate and evaluations, as exact values."""
    with h5py.File(path, "r") as f:
        e = f["subset/evaluations"]
        return (f.attrs["result_json"], {k: e[k][()] for k in e.keys()})


def same(a, b):
    if a[0] != b[0] or a[1].keys() != b[1].keys():
        return False
    return all(np.array_equal(a[1][k].view(np.uint8), b[1][k].view(np.uint8)) for k in a[1])


def run_until_level(study, out, sig, threads, level):
    """Starts `gesweep risk` and sends `sig` once its progress shows `level` done, i.e. during the next."""
    p = subprocess.Popen([GESWEEP, "risk", str(study), "-o", str(out), "--threads", str(threads)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for line in p.stderr:
        if f"level {level} done" in line:
            p.send_signal(sig)
            break
    out_text, err_rest = p.communicate(timeout=600)
    return p.returncode, out_text


def main():
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        study = write_study(tmp, "risk.toml", n=200, levels=3)
        one, two = tmp / "one.h5", tmp / "two.h5"
        r1 = risk(study, "-o", one, "--threads", 1)
        check(r1.returncode == 0, f"risk on 1 thread exits 0: {r1.returncode} {r1.stderr}")
        r2 = risk(study, "-o", two, "--threads", 2)
        check(r2.returncode == 0, f"risk on 2 threads exits 0: {r2.returncode} {r2.stderr}")
        reference = contents(one)
        check(same(reference, contents(two)), "1 and 2 threads: the same estimate and evaluations, bit for bit")
        check(r1.stdout == r2.stdout.replace("two.h5", "one.h5"), "1 and 2 threads: the same table")
        # Lanes: the landings one at a time (--lanes 1) and in 2 and 4 SIMD lanes (the default, the
        # CPU's widest, above) write the same evaluations.
        for lanes in (1, 2, 4):
            other = tmp / f"lanes{lanes}.h5"
            r = risk(study, "-o", other, "--threads", 2, "--lanes", lanes)
            check(r.returncode == 0, f"risk at --lanes {lanes} exits 0: {r.returncode} {r.stderr}")
            check(same(reference, contents(other)), f"--lanes {lanes}: the same estimate and evaluations, bit for bit")

        # 2. Kill and resume.
        cut = tmp / "cut.h5"
        code, _ = run_until_level(study, cut, signal.SIGTERM, 2, 1)
        check(code == 143, f"SIGTERM during level 2 exits 143: {code}")
        check(not cut.exists(), "a stopped run leaves no archive")
        journal = pathlib.Path(str(cut) + ".journal")
        check(journal.exists(), "a stopped run leaves its journal")
        resumed = subprocess.Popen([GESWEEP, "risk", str(study), "-o", str(cut), "--resume", "--threads", "2"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        # The second limit's first level starts after the first limit's levels: kill during it.
        for line in resumed.stderr:
            if "> 30: level 1" in line or "> 1.83: level 2 done" in line:
                resumed.send_signal(signal.SIGKILL)
                break
        resumed.communicate(timeout=600)
        check(resumed.returncode == -signal.SIGKILL or resumed.returncode == 0,
              f"the resumed run was killed (or had finished): {resumed.returncode}")
        final = risk(study, "-o", cut, "--resume", "--threads", 1)
        check(final.returncode == 0, f"--resume after SIGKILL exits 0: {final.returncode} {final.stderr}")
        if final.returncode == 0:
            check(same(reference, contents(cut)), "kill + resume: the uninterrupted estimate and evaluations, bit for bit")
            check(not journal.exists(), "a finished run removes its journal")

        # 3. Replay the last level of each limit.
        result = json.loads(reference[0])
        values_stored = reference[1]["values"]
        with h5py.File(one, "r") as f:
            columns = [c.decode() if isinstance(c, bytes) else c for c in f["subset/evaluations"].attrs["columns"]]
        replayed = 0
        for limit in range(len(result["limits"])):
            rows = np.flatnonzero(reference[1]["limit"] == limit)
            last = reference[1]["level"][rows].max()
            for row in rows[reference[1]["level"][rows] == last][:12]:
                r = risk(one, "--replay", row, "--format", "json")
                check(r.returncode == 0, f"replay of row {row} exits 0: {r.returncode} {r.stderr}")
                if r.returncode != 0:
                    continue
                j = json.loads(r.stdout)
                flown = np.array([j["values"][c.rsplit("/", 1)[-1]] for c in columns], dtype=np.float64)
                check(np.array_equal(flown.view(np.uint64), values_stored[row].view(np.uint64)),
                      f"replay of row {row}: the stored values bit for bit")
                check(j["identical"] is True, f"replay of row {row} says identical")
                replayed += 1
        check(replayed >= 12, f"at least 12 last-level rows replayed: {replayed}")

        # 4. dispersion's JSON, and the estimator's product recounted from the chain states.
        d = subprocess.run([GESWEEP, "dispersion", str(one), "--format", "json"], capture_output=True, text=True)
        check(d.returncode == 0, f"dispersion ARCHIVE --format json exits 0: {d.stderr}")
        limits = json.loads(d.stdout)["limits"]
        check(len(limits) == 2, f"two limits: {len(limits)}")
        firm, cap = limits[0], limits[1]
        for key in ("probability", "coefficient_of_variation", "interval_95", "runs", "thresholds"):
            check(key in firm and key in cap, f"dispersion JSON has {key} for each limit")
        check(firm["status"] == "converged", f"firm landing converged: {firm['status']}")
        p = firm["probability"]
        check(0 < firm["interval_95"][0] < p < firm["interval_95"][1] < 1, f"interval around P: {firm['interval_95']}")
        t = firm["thresholds"]
        check(all(a < b for a, b in zip(t, t[1:])) and t[-1] <= 1.83, f"thresholds rise to the limit: {t}")
        ev = reference[1]
        rows = ev["limit"] == 0
        check(firm["runs"] == int(rows.sum()), f"runs counts the limit's rows: {firm['runs']} vs {rows.sum()}")
        check(np.prod([lv["conditional_probability"] for lv in firm["levels"]]) == p or
              abs(np.prod([lv["conditional_probability"] for lv in firm["levels"]]) / p - 1) < 1e-12,
              "P is the product of the levels' conditional probabilities")
        # Level 1 is plain Monte Carlo: its conditional probability is the share of its N landings past
        # the first threshold, p0 by construction unless the limit itself is reached first.
        level1 = ev["g"][rows & (ev["level"] == 1)]
        check(len(level1) == 200, f"level 1 has N = 200 landings: {len(level1)}")
        column = next(i for i, c in enumerate(columns) if c.rsplit("/", 1)[-1] == firm["column"])
        sink = ev["values"][rows & (ev["level"] == 1), column]
        check(np.count_nonzero(sink > t[0]) == 20,
              f"the first threshold leaves N p0 = 20 of level 1 above it: {np.count_nonzero(sink > t[0])}")
        # 5. The unreachable limit.
        check(cap["status"] == "level_cap", f"sink > 30 m/s stops at the level cap: {cap['status']}")
        check(cap["upper_bound"] is not None and abs(cap["upper_bound"] - 0.1 ** 3) < 1e-15,
              f"its upper bound is p0^max_levels: {cap['upper_bound']}")
        check("below the level cap" in r1.stdout, "the table says the probability is below the level cap")

        # 5b. The report draws the exceedance curve and the design point from the archive.
        page = tmp / "report"
        r = subprocess.run([GESWEEP, "report", str(one), "-o", str(page), "--quiet"], capture_output=True, text=True)
        check(r.returncode == 0, f"gesweep report of a risk archive exits 0: {r.returncode} {r.stderr}")
        if r.returncode == 0:
            html = (page / "index.html").read_text()
            check("Exceedance curves by subset simulation" in html, "the report has the exceedance figure")
            check("Design point of touchdown_sink_rate_mps &gt; 1.83" in html, "the report has the firm limit's design point")
            check("Design point of touchdown_sink_rate_mps &gt; 30" not in html, "no design point for a limit no landing reached")
            pngs = sorted(p.name for p in page.glob("*.png"))
            check(any(n.endswith("_exceedance.png") for n in pngs) and any(n.endswith("_design_point.png") for n in pngs),
                  f"the figures are written: {pngs}")

        # 6. Bad inputs: one line, exit 2, nothing written.
        bad = {
            "p0": write_study(tmp, "p0.toml", subset="level_probability = 1.5\nsamples_per_level = 100"),
            "p0_zero": write_study(tmp, "p0z.toml", subset="level_probability = 0\nsamples_per_level = 100"),
            "n_fraction": write_study(tmp, "nf.toml", subset="level_probability = 0.1\nsamples_per_level = 105"),
            "n_small": write_study(tmp, "ns.toml", subset="level_probability = 0.1\nsamples_per_level = 10"),
            "column": write_study(tmp, "col.toml", limits='"touchdown_sink_mps > 3.05"'),
            "operator": write_study(tmp, "op.toml", limits='"touchdown_sink_rate_mps >= 3.05"'),
            "still_air": write_study(tmp, "still.toml", turbulence="none"),
            "sampler": write_study(tmp, "sampler.toml", subset='sampler = "gibbs"'),
        }
        expect = {
            "p0": ("level_probability", "1.5"), "p0_zero": ("level_probability", "0"),
            "n_fraction": ("samples_per_level", "105"), "n_small": ("samples_per_level", "10"),
            "column": ("limits", "touchdown_sink_mps"), "operator": ("limits", ">="),
            "still_air": ("turbulence", ""),
            "sampler": ("sampler", "gibbs"),
        }
        for name, path in bad.items():
            out = tmp / f"bad_{name}.h5"
            r = risk(path, "-o", out)
            lines = r.stderr.strip().splitlines()
            key, value = expect[name]
            check(r.returncode == 2, f"{name}: exit 2, got {r.returncode}: {r.stderr}")
            check(len(lines) == 1 and path.name in lines[0] and key in lines[0] and value in lines[0],
                  f"{name}: one line naming the file, {key} and {value!r}: {lines}")
            check(not out.exists() and not pathlib.Path(str(out) + ".journal").exists(), f"{name}: nothing written")
            if name == "sampler":  # the choices, from the samplers' names table
                check("crank_nicolson" in lines[0] and "modified_metropolis" in lines[0],
                      f"sampler: the line names the samplers: {lines}")
        # An existing archive is never overwritten.
        r = risk(study, "-o", one)
        check(r.returncode == 2 and "exists" in r.stderr, f"an existing -o is refused: {r.returncode} {r.stderr}")
        check(same(reference, contents(one)), "the refused run left the archive as it was")
        # A replay row out of range.
        r = risk(one, "--replay", 10 ** 9)
        check(r.returncode == 2 and "--replay" in r.stderr, f"--replay past the rows: exit 2: {r.stderr}")

        # 7. Independent repetitions: K runs, their first the run without repetitions (the same seed),
        # pooled as the mean with the spread measured (recomputed here from the runs' estimates).
        reps = write_study(tmp, "reps.toml", limits='"touchdown_sink_rate_mps > 1.83"',
                           subset=SUBSET.format(n=200, levels=3) + "\nrepetitions = 3")
        pooled_archive = tmp / "reps.h5"
        r = risk(reps, "-o", pooled_archive, "--threads", 2)
        check(r.returncode == 0, f"risk with repetitions exits 0: {r.returncode} {r.stderr}")
        check("measured over 3 repetitions" in r.stdout, f"the table says the CoV is measured: {r.stdout}")
        if r.returncode == 0:
            d = subprocess.run([GESWEEP, "dispersion", str(pooled_archive), "--format", "json"],
                               capture_output=True, text=True)
            limit = json.loads(d.stdout)["limits"][0]
            estimates = limit["repetitions"]["estimates"]
            check(limit["repetitions"]["count"] == 3 and len(estimates) == 3, f"three repetitions: {limit['repetitions']}")
            check(estimates[0]["probability"] == firm["probability"],
                  f"repetition 0 is the run without repetitions: {estimates[0]['probability']} vs {firm['probability']}")
            check(len({e["seed"] for e in estimates}) == 3, "each repetition has its own seed")
            ps = np.array([e["probability"] for e in estimates])
            check(abs(limit["probability"] / ps.mean() - 1) < 1e-14, f"P is the mean of the runs: {limit['probability']} vs {ps}")
            measured = ps.std(ddof=1) / ps.mean()
            check(abs(limit["coefficient_of_variation"] / (measured / np.sqrt(3)) - 1) < 1e-12,
                  f"the CoV is the measured spread over sqrt(K): {limit['coefficient_of_variation']} vs {measured / np.sqrt(3)}")
            check(abs(limit["repetitions"]["measured_coefficient_of_variation_one_run"] / measured - 1) < 1e-12,
                  "one run's measured CoV is the spread of the runs")
            check(limit["interval_95"][0] < limit["probability"] < limit["interval_95"][1], f"interval around P: {limit['interval_95']}")
            stored = contents(pooled_archive)[1]
            check(sorted(set(stored["repetition"].tolist())) == [0, 1, 2], "the archive tags each landing's repetition")
            check(limit["runs"] == len(stored["g"]) == sum(e["runs"] for e in estimates),
                  f"runs: all the repetitions' landings: {limit['runs']} vs {len(stored['g'])}")
            rows = np.flatnonzero(stored["repetition"] == 2)
            row = rows[stored["level"][rows] == stored["level"][rows].max()][0]
            rp = risk(pooled_archive, "--replay", row, "--format", "json")
            check(rp.returncode == 0 and json.loads(rp.stdout)["identical"] is True and json.loads(rp.stdout)["repetition"] == 2,
                  f"a last-level landing of repetition 2 replays bit for bit: {rp.returncode} {rp.stderr}")
        bad_reps = write_study(tmp, "bad_reps.toml", subset=SUBSET.format(n=200, levels=3) + "\nrepetitions = 0")
        r = risk(bad_reps, "-o", tmp / "bad_reps.h5")
        lines = r.stderr.strip().splitlines()
        check(r.returncode == 2 and len(lines) == 1 and "bad_reps.toml" in lines[0] and "repetitions" in lines[0]
              and "0" in lines[0], f"repetitions = 0: one line, exit 2: {r.returncode} {lines}")
        check(not (tmp / "bad_reps.h5").exists(), "repetitions = 0: nothing written")

        # 8. The collapse line: the table prints COLLAPSED when a run of more than two levels ends in a
        # level that descends from fewer than a tenth of its chains (here N p0 = 20: 1 ancestor is, 2 is
        # not). The rule is checked on a copy of the archive with the diagnostic set by hand.
        for ancestors, expected in ((1, True), (2, False)):
            copy = tmp / f"collapsed_{ancestors}.h5"
            copy.write_bytes(one.read_bytes())
            with h5py.File(copy, "r+") as f:
                j = json.loads(f.attrs["result_json"])
                j["limits"][1]["last_level_ancestors"] = ancestors
                f.attrs["result_json"] = json.dumps(j)
            d = subprocess.run([GESWEEP, "dispersion", str(copy)], capture_output=True, text=True)
            line = next((l for l in d.stdout.splitlines() if "> 30" in l), "")
            check(("COLLAPSED" in line) == expected, f"{ancestors} ancestor(s) of 20 chains: COLLAPSED {expected}: {line}")
        check(all("COLLAPSED" not in l for l in r1.stdout.splitlines()), "the test's own runs did not collapse")

        random_parameters(tmp)
        gust_parameters(tmp)

    if failures:
        print(f"{len(failures)} failures")
        sys.exit(1)
    print("risk CLI: threads, kill + resume, replay, dispersion JSON, level cap and bad inputs hold")


def write_random(directory, filename, **fields):
    defaults = dict(aircraft=ANCE, analyses="", kind="monte_carlo", more_parameters="",
                    parameters="height_m = 30.0\nspeed_mps = 52.21", subset=SUBSET.format(n=300, levels=6))
    defaults.update(fields)
    path = pathlib.Path(directory) / filename
    path.write_text(RANDOM_STUDY.format(**defaults))
    return path


def dispersion_json(archive):
    d = subprocess.run([GESWEEP, "dispersion", str(archive), "--format", "json"], capture_output=True, text=True)
    return json.loads(d.stdout)["limits"] if d.returncode == 0 else []


def random_parameters(tmp):
    """Section 9: a monte_carlo design's parameters join the standard-normal space."""
    linear = "[analyses.linear]\ncoefficients = [1.0]"
    for label, distribution, limit, truth in (("normal", "normal = [0.0, 1.0]", "linear > 3.0", PHI_MINUS_3),
                                              ("uniform", "uniform = [0.0, 1.0]", "linear > 0.999", 1e-3)):
        study = write_random(tmp, f"random_{label}.toml", analyses=linear, name="x1", distribution=distribution,
                             limits=f'"{limit}"', subset=SUBSET.format(n=300, levels=6) + "\nrepetitions = 10")
        archive = tmp / f"random_{label}.h5"
        r = risk(study, "-o", archive, "--threads", 2)
        check(r.returncode == 0, f"{label}: risk exits 0: {r.returncode} {r.stderr}")
        limits = dispersion_json(archive)
        if not limits:
            check(False, f"{label}: dispersion JSON of the archive")
            continue
        l = limits[0]
        p, cov = l["probability"], l["coefficient_of_variation"]
        check(l["dimension"] == 1, f"{label}: a still-air landing and one random parameter: dimension 1, not {l['dimension']}")
        check(abs(p - truth) < ORACLE_SIGMAS * cov * p,
              f"{label}: P(x1 ~ {distribution}: {limit}) = {p:.4g} (CoV {cov:.3g}) within {ORACLE_SIGMAS} CoV of {truth:.6g}")
        check("x1 ~ " in l["cell_label"], f"{label}: the cell is labelled by the distribution: {l['cell_label']}")
        point = l["design_point"]["random_parameters"][0]
        check(point["name"] == "x1" and point["median"] == (0.0 if label == "normal" else 0.5),
              f"{label}: the random parameter's median: {point}")
        if label == "normal":
            # A linear limit state's design point is at beta = 3 along x1 (x1 is its own coordinate).
            check(3.0 < point["most_likely"] < 3.0 + DESIGN_POINT_SLACK,
                  f"normal: the most likely failing x1 just above beta = 3: {point['most_likely']}")
            check(point["most_likely"] == l["design_point"]["most_likely_distance"],
                  "normal: x1 = z, so the most likely value is its distance from the origin")

    # A random headwind in turbulence: the wind's coordinate comes after the noise's.
    wind = dict(parameters="height_m = 30.0\nspeed_mps = 52.21\nwind_shear = \"logarithmic\"\nturbulence = \"dryden\"",
                name="wind_20ft_mps", distribution="normal = [-15.433333, 2.0]",
                limits='"touchdown_sink_rate_mps > 1.83"', subset=SUBSET.format(n=100, levels=3))
    study = write_random(tmp, "random_wind.toml", **wind)
    fixed = write_study(tmp, "fixed_wind.toml", limits='"touchdown_sink_rate_mps > 1.83"',
                        subset=SUBSET.format(n=100, levels=1))
    one, two, fixed_out = tmp / "random_wind_1.h5", tmp / "random_wind_2.h5", tmp / "fixed_wind.h5"
    r1, r2 = risk(study, "-o", one, "--threads", 1), risk(study, "-o", two, "--threads", 2)
    rf = risk(fixed, "-o", fixed_out)
    check(r1.returncode == 0 and r2.returncode == 0 and rf.returncode == 0,
          f"random wind: risk exits 0: {r1.stderr} {r2.stderr} {rf.stderr}")
    if r1.returncode == 0 and r2.returncode == 0 and rf.returncode == 0:
        check(same(contents(one), contents(two)), "random wind: 1 and 2 threads, the same estimate and evaluations")
        l, lf = dispersion_json(one)[0], dispersion_json(fixed_out)[0]
        check(l["dimension"] == lf["dimension"] + 1,
              f"random wind: the noise's coordinates and one more: {l['dimension']} vs {lf['dimension']} + 1")
        stored = contents(one)[1]
        last = np.flatnonzero(stored["level"] == stored["level"].max())
        for row in last[:: max(1, len(last) // 6)]:
            rp = risk(one, "--replay", row, "--format", "json")
            check(rp.returncode == 0 and json.loads(rp.stdout)["identical"] is True,
                  f"random wind: last-level row {row} replays bit for bit: {rp.returncode} {rp.stderr}")

    # Refused with one line, nothing written: a random start height (it lengthens the landing's noise),
    # and a design whose rows are not random draws (lhs).
    height = dict(wind, name="height_m", distribution="uniform = [20.0, 40.0]",
                  parameters="wind_20ft_mps = -15.433333\nspeed_mps = 52.21\nturbulence = \"dryden\"")
    lhs = dict(wind, kind="lhs", distribution="uniform = [-20.0, -10.0]")
    for name, fields, key, value in (("random_height", height, "parameters.height_m", "40"),
                                     ("random_lhs", lhs, "design.kind", "lhs")):
        path = write_random(tmp, f"{name}.toml", **fields)
        out = tmp / f"{name}.h5"
        r = risk(path, "-o", out)
        lines = r.stderr.strip().splitlines()
        check(r.returncode == 2 and len(lines) == 1 and path.name in lines[0] and key in lines[0] and value in lines[0],
              f"{name}: one line naming the file, {key} and {value}, exit 2: {r.returncode} {lines}")
        check(not out.exists(), f"{name}: nothing written")


def gust_landing(amplitude, half_length):
    """The summary of a deterministic `gesweep land` run of section 10's landing with this gust."""
    r = subprocess.run([GESWEEP, "land", "--aircraft", str(ANCE), "--start-height-m", "30", "--start-speed-mps", "52.21",
                        "--summary-only", "--format", "json", "--gust-axis", "w", "--gust-amplitude-mps", repr(amplitude),
                        "--gust-half-length-m", repr(half_length), "--gust-start-s", repr(GUST_START_S)],
                       capture_output=True, text=True, check=True)
    return json.loads(r.stdout)["summary"]


def gust_sink(amplitude, half_length):
    summary = gust_landing(amplitude, half_length)
    return summary["touchdown_sink_rate_mps"] if summary["outcome"] == "landed" else float("nan")


def gust_threshold(half_length):
    """a*(d): the amplitude past which the landing's sink rate exceeds the limit, by bisection on
    deterministic landings, after checking the sink rate is below the limit from mu - 5 sigma up to it
    and above it from there to mu + 6 sigma (on a coarse grid: the event is {amplitude > a*})."""
    low, high = GUST_MEAN_MPS, GUST_MEAN_MPS + 6 * GUST_SIGMA_MPS
    check(gust_sink(low, half_length) < GUST_LIMIT_MPS < gust_sink(high, half_length),
          f"gust: the limit is crossed between {low} and {high} m/s at d = {half_length}")
    while high - low > GUST_BISECTION_WIDTH_MPS:
        middle = 0.5 * (low + high)
        if gust_sink(middle, half_length) > GUST_LIMIT_MPS:
            high = middle
        else:
            low = middle
    threshold = 0.5 * (low + high)
    below = np.linspace(GUST_MEAN_MPS - 5 * GUST_SIGMA_MPS, low, 6)
    above = np.linspace(high, GUST_MEAN_MPS + 6 * GUST_SIGMA_MPS, 4)
    check(all(gust_sink(a, half_length) <= GUST_LIMIT_MPS for a in below) and
          all(gust_sink(a, half_length) > GUST_LIMIT_MPS for a in above),
          f"gust: at d = {half_length} m the sink rate passes {GUST_LIMIT_MPS} once, at a* = {threshold:.5f} m/s")
    return threshold


def normal_upper_tail(beta):
    return 0.5 * math.erfc(beta / math.sqrt(2.0))


def gust_parameters(tmp):
    """Section 10: the 1 - cos gust's amplitude and half-length as random parameters."""
    # The truth: P = (1/(d1 - d0)) * integral of Phi(-(a*(d) - mu)/sigma) over d, by Gauss-Legendre.
    nodes, weights = np.polynomial.legendre.leggauss(GUST_NODES)
    d0, d1 = GUST_HALF_LENGTHS_M
    half_lengths = 0.5 * (d0 + d1) + 0.5 * (d1 - d0) * nodes
    thresholds = [gust_threshold(d) for d in half_lengths]
    truth = sum(0.5 * w * normal_upper_tail((a - GUST_MEAN_MPS) / GUST_SIGMA_MPS) for w, a in zip(weights, thresholds))

    study = write_random(tmp, "random_gust.toml", name="gust_amplitude_mps",
                         parameters=f"height_m = 30.0\nspeed_mps = 52.21\ngust_axis = \"w\"\ngust_start_s = {GUST_START_S}",
                         distribution=f"normal = [{GUST_MEAN_MPS}, {GUST_SIGMA_MPS}]",
                         more_parameters=f"[[design.parameter]]\nname = \"gust_half_length_m\"\nuniform = [{d0}, {d1}]",
                         limits=f'"touchdown_sink_rate_mps > {GUST_LIMIT_MPS}"',
                         subset=SUBSET.format(n=300, levels=6) + "\nrepetitions = 10")
    archive = tmp / "random_gust.h5"
    r = risk(study, "-o", archive, "--threads", 2)
    check(r.returncode == 0, f"gust: risk exits 0: {r.returncode} {r.stderr}")
    limits = dispersion_json(archive)
    if r.returncode != 0 or not limits:
        check(False, "gust: dispersion JSON of the archive")
        return
    l = limits[0]
    p, cov = l["probability"], l["coefficient_of_variation"]
    print(f"gust: a*(d) = {np.round(thresholds, 5).tolist()} m/s at d = {np.round(half_lengths, 3).tolist()} m; "
          f"truth {truth:.5g}, estimate {p:.5g} (CoV {cov:.3g})")
    check(l["dimension"] == 2, f"gust: a still-air landing and two random parameters: dimension 2, not {l['dimension']}")
    check(abs(p - truth) < ORACLE_SIGMAS * cov * p,
          f"gust: P(sink > {GUST_LIMIT_MPS}) = {p:.4g} (CoV {cov:.3g}) within {ORACLE_SIGMAS} CoV of {truth:.6g}")
    measured = l["repetitions"]["measured_coefficient_of_variation_one_run"]
    stated = l["repetitions"]["estimates"][0]["coefficient_of_variation"]
    check(1 / COV_RATIO_BOUND < stated / measured < COV_RATIO_BOUND,
          f"gust: one run's stated CoV {stated:.3g} within a factor {COV_RATIO_BOUND} of the measured {measured:.3g}")
    amplitude, half_length = l["design_point"]["random_parameters"]
    check(amplitude["name"] == "gust_amplitude_mps" and amplitude["median"] == GUST_MEAN_MPS and
          half_length["name"] == "gust_half_length_m" and half_length["median"] == 0.5 * (d0 + d1),
          f"gust: the random parameters' medians: {amplitude} {half_length}")
    # The most likely failing landing: past a* at its own half-length, and the deterministic landing
    # at its parameter values is the stored evaluation, bit for bit.
    a_most, d_most = amplitude["most_likely"], half_length["most_likely"]
    check(d0 <= d_most <= d1, f"gust: the most likely half-length within the uniform's range: {d_most}")
    threshold_there = gust_threshold(d_most)
    check(threshold_there - GUST_BISECTION_WIDTH_MPS < a_most < threshold_there + GUST_DESIGN_POINT_SLACK_MPS,
          f"gust: the most likely failing amplitude {a_most:.5f} just past a*({d_most:.3f} m) = {threshold_there:.5f}")
    stored = contents(archive)[1]
    with h5py.File(archive, "r") as f:
        columns = [c.decode() if isinstance(c, bytes) else c for c in f["subset/evaluations"].attrs["columns"]]
    flown = gust_landing(a_most, d_most)
    row = stored["values"][l["design_point"]["most_likely_row"]]
    numbers = [(c.rsplit("/", 1)[-1], v) for c, v in zip(columns, row) if c.rsplit("/", 1)[-1] in flown
               and c.rsplit("/", 1)[-1] != "outcome"]
    check(len(numbers) >= 20 and all(np.float64(flown[k]).view(np.uint64) == np.float64(v).view(np.uint64) for k, v in numbers),
          "gust: `gesweep land` at the most likely point's amplitude and half-length is its stored landing, bit for bit")
    # Last-level landings of the first and of the last repetition replay bit for bit.
    for repetition in (0, 9):
        rows = np.flatnonzero(stored["repetition"] == repetition)
        last = rows[stored["level"][rows] == stored["level"][rows].max()]
        for row in last[:: max(1, len(last) // 4)][:4]:
            rp = risk(archive, "--replay", row, "--format", "json")
            check(rp.returncode == 0 and json.loads(rp.stdout)["identical"] is True,
                  f"gust: last-level row {row} (repetition {repetition}) replays bit for bit: {rp.returncode} {rp.stderr}")


if __name__ == "__main__":
    main()
