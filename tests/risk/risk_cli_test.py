#!/usr/bin/python3
"""`gesweep risk`: the landing risk by subset simulation, end to end (issue 27; docs/dispersion.md,
"Landing risk by subset simulation").

    /usr/bin/python3 tests/risk/risk_cli_test.py GESWEEP

The oracles are the engine's own uninterrupted, single-threaded run (an identity, not a number it
produced): what is checked is that the estimate does not depend on how it was reached.
1. Threads: the same study on 1 and on 2 threads writes the same estimate (result_json) and the same
   evaluations, bit for bit.
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
   lhs design refused with one line."""
import json
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
        }
        expect = {
            "p0": ("level_probability", "1.5"), "p0_zero": ("level_probability", "0"),
            "n_fraction": ("samples_per_level", "105"), "n_small": ("samples_per_level", "10"),
            "column": ("limits", "touchdown_sink_mps"), "operator": ("limits", ">="),
            "still_air": ("turbulence", ""),
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

    if failures:
        print(f"{len(failures)} failures")
        sys.exit(1)
    print("risk CLI: threads, kill + resume, replay, dispersion JSON, level cap and bad inputs hold")


def write_random(directory, filename, **fields):
    defaults = dict(aircraft=ANCE, analyses="", kind="monte_carlo",
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


if __name__ == "__main__":
    main()
