#!/usr/bin/python3
"""`gesweep dispersion` and the monte_carlo design against NumPy/SciPy (docs/dispersion.md).

1. A monte_carlo study of the Ishigami function (a truncated normal, a normal, a weighted discrete
   parameter) is run; every design row is recomputed here from (seed, run index, parameter name)
   alone, with this file's own SplitMix64/FNV-1a and scipy.stats quantiles.
2. `gesweep dispersion --group-by x3` with limits on both sides: per group, the counts, mean, std,
   percentiles (numpy.percentile), norm.fit, gumbel_r.fit, gumbel_l.fit, scipy.stats.anderson
   (normal and gumbel_r/gumbel_l statistics, critical values), binomtest's Wilson and exact
   (Clopper-Pearson) intervals, the fitted tail quantiles and probabilities; the JSON and the written
   /analysis/dispersion product agree.
3. A small landing Monte Carlo: the default columns are the touchdown columns, and the counts add up
   (failed and without-value runs reported).

Usage: peer_dispersion_test.py --gesweep BUILD/gesweep
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np
from scipy import stats

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
GESWEEP = None

# Sums and variances: the engine adds in run order, NumPy pairwise; both are within a few ulps of
# the exact value for 4000 values of order 10.
kMomentRelative = 1e-12
# The maximum-likelihood fits: the engine solves the Gumbel likelihood equation by TOMS 748 to full
# precision on standardised values, SciPy by its own root finder; the scale agrees to about 1e-12,
# and the location (a log of a sum) to the same. 1e-9 leaves margin for SciPy's solver tolerance.
kFitRelative = 1e-9
# Quantiles and tail probabilities computed from the fits inherit kFitRelative, amplified in the far
# tail (10^-6: the Gumbel quantile's sensitivity to β is y = 13.8, the normal tail's to σ is z² = 23).
kTailRelative = 1e-7
# Anderson-Darling: sums of logs of the fitted CDF; the fit's relative error times n (4000) bounds it.
kAndersonAbsolute = 1e-6
# Binomial intervals: Boost's incomplete-beta inverse and SciPy's beta.ppf, both to about 1e-14.
kIntervalAbsolute = 1e-12
# The GEV fit: SciPy's genextreme.fit stops its Nelder-Mead at xtol = ftol = 1e-4 on its own scale,
# so it may sit a little below the maximum: the engine's log-likelihood must be at least as high
# (within 1e-6 of round-off), and its shape within 1e-3 of SciPy's.
kGevLikelihood = 1e-6
kGevShape = 1e-3
# Design rows: Boost's normal quantile against scipy.special.ndtri, both within a few ulps;
# the truncated normal is computed by different formulas (the engine mirrors intervals above the
# mean, SciPy's truncnorm uses its own log-space method), agreeing to about 1e-12 relative.
kRowRelative = 1e-10

MASK = (1 << 64) - 1


def mix64(x):
    """engine/sweep/hashing.h's Mix64 (SplitMix64's step and finaliser)."""
    x = (x + 0x9E3779B97F4A7C15) & MASK
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & MASK
    return x ^ (x >> 31)


def hash_words(a, b, c=0, d=0):
    return mix64(mix64(mix64(mix64(a) ^ b) ^ c) ^ d)


def fnv1a64(text):
    state = 0xCBF29CE484222325
    for byte in text.encode():
        state ^= byte
        state = (state * 0x100000001B3) & MASK
    return state


MONTE_CARLO_TAG = 0x4D4F4E54455F4341  # "MONTE_CA"


def unit(seed, index, name):
    run_key = hash_words(seed ^ MONTE_CARLO_TAG, index)
    bits = hash_words(run_key, fnv1a64(name))
    return ((bits >> 12) + 0.5) * 2.0**-52


SEED = 20261202
SAMPLES = 4000
STUDY = f"""format_version = 1
name = "peer_dispersion"
[analyses.ishigami]
a = 7.0
b = 0.1
[design]
kind = "monte_carlo"
samples = {SAMPLES}
seed = {SEED}
[[design.parameter]]
name = "x1"
truncated_normal = [0.5, 1.0, -1.0, 3.0]
[[design.parameter]]
name = "x2"
normal = [0.0, 0.3]
[[design.parameter]]
name = "x3"
values = [-1.0, 0.0, 2.0]
weights = [1.0, 2.0, 1.5]
"""
LIMITS = ["ishigami>6", "ishigami<-1"]
PERCENTILES = [0.1, 1, 5, 50, 95, 99, 99.9]
TAILS = [1e-3, 1e-4, 1e-5, 1e-6]


def run(*args):
    result = subprocess.run([GESWEEP, *args], capture_output=True, text=True)
    if result.returncode != 0:
        raise AssertionError(f"gesweep {' '.join(args)}: exit {result.returncode}: {result.stderr}")
    return result.stdout


class PeerDispersionTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = tempfile.mkdtemp(prefix="gesweep_peer_dispersion_")
        study = os.path.join(cls.directory, "mc.toml")
        with open(study, "w") as f:
            f.write(STUDY)
        cls.archive = os.path.join(cls.directory, "mc.h5")
        run("run", study, "-o", cls.archive)
        args = ["dispersion", cls.archive, "--columns", "ishigami", "--group-by", "x3", "--format", "json"]
        for limit in LIMITS:
            args += ["--limit", limit]
        cls.result = json.loads(run(*args))
        with h5py.File(cls.archive, "r") as f:
            cls.x = {name: f[f"design/{name}"][:] for name in ("x1", "x2", "x3")}
            cls.y = f["results/ishigami/ishigami"][:]
            cls.status = f["runs/status"][:]
            cls.product = {k: v[()] for k, v in f["analysis/dispersion"].items() if isinstance(v, h5py.Dataset)}
            cls.product_limits = {k: v[()] for k, v in f["analysis/dispersion/limits"].items()}

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.directory, ignore_errors=True)

    def test_every_row_recomputed_alone_equals_the_archive(self):
        for i in range(SAMPLES):
            u1, u2, u3 = (unit(SEED, i, name) for name in ("x1", "x2", "x3"))
            a, b = (-1.0 - 0.5) / 1.0, (3.0 - 0.5) / 1.0
            x1 = stats.truncnorm.ppf(u1, a, b, loc=0.5, scale=1.0)
            x2 = stats.norm.ppf(u2, loc=0.0, scale=0.3)
            cumulative = np.cumsum([1.0, 2.0, 1.5])
            x3 = [-1.0, 0.0, 2.0][int(np.searchsorted(cumulative, u3 * cumulative[-1], side="right"))]
            self.assertAlmostEqual(self.x["x1"][i], x1, delta=kRowRelative * max(1.0, abs(x1)), msg=f"row {i}")
            self.assertAlmostEqual(self.x["x2"][i], x2, delta=kRowRelative * max(1.0, abs(x2)), msg=f"row {i}")
            self.assertEqual(self.x["x3"][i], x3, msg=f"row {i}")

    def test_samples_follow_their_distributions(self):
        # KS against the analytic CDFs at significance 0.001 (the sample is fixed by the seed).
        self.assertGreater(stats.kstest(self.x["x1"], stats.truncnorm(-1.5, 2.5, loc=0.5, scale=1.0).cdf).pvalue, 1e-3)
        self.assertGreater(stats.kstest(self.x["x2"], stats.norm(0, 0.3).cdf).pvalue, 1e-3)

    def groups(self):
        keys = np.unique(self.x["x3"])
        self.assertEqual([g["value"] for g in self.result["groups"]], list(keys))
        for g, key in zip(self.result["groups"], keys):
            mask = self.x["x3"] == key
            values = self.y[mask & (self.status == 1) & np.isfinite(self.y)]
            yield g, mask, values

    def close(self, actual, expected, relative, what):
        self.assertTrue(math.isclose(actual, expected, rel_tol=relative, abs_tol=relative),
                        f"{what}: engine {actual!r}, SciPy {expected!r}")

    def test_moments_percentiles_and_counts(self):
        for g, mask, values in self.groups():
            c = g["columns"][0]
            self.assertEqual(c["runs"], int(mask.sum()))
            self.assertEqual(c["values"], len(values))
            self.assertEqual(c["failed"], int((self.status[mask] == 2).sum()))
            self.close(c["mean"], np.mean(values), kMomentRelative, "mean")
            self.close(c["standard_deviation"], np.std(values, ddof=1), kMomentRelative, "std")
            for p, engine in zip(PERCENTILES, c["percentiles"]):
                self.close(engine, np.percentile(values, p), kMomentRelative, f"percentile {p}")

    def test_list_flags_replace_their_defaults_and_a_bad_element_is_one_line(self):
        # --percentiles and --tail-probabilities take comma-separated lists (a described list field):
        # the lists given replace the defaults, and the percentiles are NumPy's of each group.
        percentiles, tails = [2.5, 50, 97.5], [1e-2]
        result = json.loads(run("dispersion", self.archive, "--columns", "ishigami", "--group-by", "x3",
                                "--percentiles", "2.5,50,97.5", "--tail-probabilities", "1e-2", "--format",
                                "json", "--no-write"))
        self.assertEqual(result["percentiles"], percentiles)
        self.assertEqual(result["tail_probabilities"], tails)
        for g, (_, _, values) in zip(result["groups"], self.groups()):
            c = g["columns"][0]
            self.assertEqual(len(c["percentiles"]), len(percentiles))
            for p, engine in zip(percentiles, c["percentiles"]):
                self.close(engine, np.percentile(values, p), kMomentRelative, f"percentile {p}")
            normal = next(f for f in c["fits"] if f["law"] == "normal")
            self.assertEqual(len(normal["upper_quantiles"]), len(tails))
        for flag, value, words in (("--percentiles", "5,abc", "Could not convert"),
                                   ("--percentiles", "5,150", "expected 0 to 100"),
                                   ("--tail-probabilities", "1e-3,0.7", "expected a probability in [1e-12, 0.5)")):
            bad = subprocess.run([GESWEEP, "dispersion", self.archive, "--no-write", flag, value],
                                 capture_output=True, text=True)
            self.assertEqual(bad.returncode, 2, bad.stderr)
            self.assertEqual(len(bad.stderr.splitlines()), 1, bad.stderr)
            self.assertIn(flag, bad.stderr)
            self.assertIn(words, bad.stderr)

    def test_fits_goodness_and_tails(self):
        for g, _, values in self.groups():
            normal, gmax, gmin, gev = g["columns"][0]["fits"]
            loc, scale = stats.norm.fit(values)
            self.close(normal["location"], loc, kFitRelative, "norm.fit loc")
            self.close(normal["scale"], scale, kFitRelative, "norm.fit scale")
            loc_r, scale_r = stats.gumbel_r.fit(values)
            self.close(gmax["location"], loc_r, kFitRelative, "gumbel_r.fit loc")
            self.close(gmax["scale"], scale_r, kFitRelative, "gumbel_r.fit scale")
            loc_l, scale_l = stats.gumbel_l.fit(values)
            self.close(gmin["location"], loc_l, kFitRelative, "gumbel_l.fit loc")
            self.close(gmin["scale"], scale_l, kFitRelative, "gumbel_l.fit scale")
            for fit, dist in ((normal, "norm"), (gmax, "gumbel_r"), (gmin, "gumbel_l")):
                ad = stats.anderson(values, dist)
                self.assertAlmostEqual(fit["anderson_darling"], ad.statistic, delta=kAndersonAbsolute, msg=dist)
                self.assertEqual(fit["critical_values"], list(ad.critical_values), dist)
                self.assertEqual(fit["significance_percent"], list(ad.significance_level), dist)
            # GEV: SciPy's genextreme.fit (Nelder-Mead from its own start) and the engine's fit; the
            # engine's likelihood is at least as high, and the parameters agree to the optimisers'
            # tolerances (kGevShape on ξ).
            c, loc_g, scale_g = stats.genextreme.fit(values)
            nll = lambda c_, l_, s_: -np.sum(stats.genextreme.logpdf(values, c_, l_, s_))
            self.assertLessEqual(nll(-gev["shape"], gev["location"], gev["scale"]),
                                 nll(c, loc_g, scale_g) + kGevLikelihood)
            self.assertAlmostEqual(gev["shape"], -c, delta=kGevShape)
            for p, q in zip(TAILS, gev["upper_quantiles"]):
                self.close(q, stats.genextreme.isf(p, -gev["shape"], gev["location"], gev["scale"]), kTailRelative,
                           f"gev upper {p}")
            for p, up, low, gup, glow in zip(TAILS, normal["upper_quantiles"], normal["lower_quantiles"],
                                             gmax["upper_quantiles"], gmin["lower_quantiles"]):
                self.close(up, stats.norm.isf(p, loc, scale), kTailRelative, f"normal upper {p}")
                self.close(low, stats.norm.ppf(p, loc, scale), kTailRelative, f"normal lower {p}")
                self.close(gup, stats.gumbel_r.isf(p, loc_r, scale_r), kTailRelative, f"gumbel upper {p}")
                self.close(glow, stats.gumbel_l.ppf(p, loc_l, scale_l), kTailRelative, f"gumbel lower {p}")

    def test_limit_exceedance_and_intervals(self):
        for g, _, values in self.groups():
            for text, e in zip(LIMITS, g["limits"]):
                above = ">" in text
                limit = float(text.split(">" if above else "<")[1])
                k = int((values > limit).sum() if above else (values < limit).sum())
                n = len(values)
                self.assertEqual((e["exceed"], e["values"]), (k, n), text)
                self.assertEqual(e["probability"], k / n)
                test = stats.binomtest(k, n)
                wilson = test.proportion_ci(0.95, method="wilson")
                exact = test.proportion_ci(0.95, method="exact")
                self.assertAlmostEqual(e["wilson"][0], wilson.low, delta=kIntervalAbsolute, msg=text)
                self.assertAlmostEqual(e["wilson"][1], wilson.high, delta=kIntervalAbsolute, msg=text)
                self.assertAlmostEqual(e["clopper_pearson"][0], exact.low, delta=kIntervalAbsolute, msg=text)
                self.assertAlmostEqual(e["clopper_pearson"][1], exact.high, delta=kIntervalAbsolute, msg=text)
                loc, scale = stats.norm.fit(values)
                if above:
                    normal = stats.norm.sf(limit, loc, scale)
                    gumbel = stats.gumbel_r.sf(limit, *stats.gumbel_r.fit(values))
                else:
                    normal = stats.norm.cdf(limit, loc, scale)
                    gumbel = stats.gumbel_l.cdf(limit, *stats.gumbel_l.fit(values))
                self.close(e["normal_probability"], normal, kTailRelative, text + " normal")
                self.close(e["gumbel_probability"], gumbel, kTailRelative, text + " gumbel")

    def test_written_product_equals_the_printed_one(self):
        groups = self.result["groups"]
        self.assertEqual([v for v in self.product["group_value"]], [g["value"] for g in groups])
        for i, g in enumerate(groups):
            c = g["columns"][0]
            self.assertEqual(self.product["mean"][i][0], c["mean"])
            self.assertEqual(self.product["values"][i][0], c["values"])
            self.assertEqual(list(self.product["percentile_values"][i][0]), c["percentiles"])
            self.assertEqual(list(self.product["gumbel_max_upper_quantiles"][i][0]), c["fits"][1]["upper_quantiles"])
            for l, e in enumerate(g["limits"]):
                self.assertEqual(self.product_limits["clopper_pearson_upper"][i][l], e["clopper_pearson"][1])
                self.assertEqual(self.product_limits["exceed"][i][l], e["exceed"])


class FailedRunsTest(unittest.TestCase):
    def test_failed_runs_are_counted_per_group_and_kept_out_of_the_sample(self):
        # An absurd mass and inertia overflow the state matrix: those runs fail (tests/e2e's oracle).
        directory = tempfile.mkdtemp(prefix="gesweep_peer_dispersion_failed_")
        try:
            study = os.path.join(directory, "failed.toml")
            with open(study, "w") as f:
                f.write(f"""format_version = 1
name = "peer_dispersion_failed"
aircraft = "{REPO}/studies/aircraft/ance.toml"
[analyses.modes]
[parameters]
speed_mps = 32
height_m = 2
[design]
kind = "list"
columns = ["mass_kg", "pitch_inertia_kgm2"]
rows = [[182.055, 400.0], [1e-300, 1e-300], [200.0, 420.0], [1e-300, 1e-300], [182.055, 410.0]]
""")
            archive = os.path.join(directory, "failed.h5")
            self.assertEqual(subprocess.run([GESWEEP, "run", study, "-o", archive], capture_output=True).returncode, 3)
            result = json.loads(run("dispersion", archive, "--columns", "stability_margin_per_s", "--group-by",
                                    "mass_kg", "--limit", "stability_margin_per_s>0", "--format", "json"))
            with h5py.File(archive, "r") as f:
                sigma = f["results/modes/stability_margin_per_s"][:]
                status = f["runs/status"][:]
                mass = f["design/mass_kg"][:]
            for g in result["groups"]:
                mask = mass == g["value"]
                c, e = g["columns"][0], g["limits"][0]
                self.assertEqual(c["failed"], int((status[mask] == 2).sum()))
                self.assertEqual(c["values"], int((mask & (status == 1)).sum()))
                self.assertEqual(e["failed"], c["failed"] + c["without_value"])
                self.assertEqual(e["exceed"], int((sigma[mask & (status == 1)] > 0).sum()))
            self.assertEqual(sum(g["columns"][0]["failed"] for g in result["groups"]), 2)
        finally:
            shutil.rmtree(directory, ignore_errors=True)


class LandingDefaultsTest(unittest.TestCase):
    def test_default_columns_are_the_touchdown_columns_and_counts_add_up(self):
        directory = tempfile.mkdtemp(prefix="gesweep_peer_dispersion_landing_")
        try:
            study = os.path.join(directory, "landing.toml")
            with open(study, "w") as f:
                f.write(f"""format_version = 1
name = "peer_dispersion_landing"
aircraft = "{REPO}/studies/aircraft/ance.toml"
[analyses.landing]
[parameters]
height_m = 30.0
[design]
kind = "monte_carlo"
samples = 24
seed = 3
[[design.parameter]]
name = "speed_mps"
truncated_normal = [52.0, 1.5, 48.0, 56.0]
[[design.parameter]]
name = "glide_slope_deg"
uniform = [2.5, 3.5]
""")
            archive = os.path.join(directory, "landing.h5")
            subprocess.run([GESWEEP, "run", study, "-o", archive], capture_output=True, text=True)
            result = json.loads(run("dispersion", archive, "--format", "json", "--no-write",
                                    "--limit", "touchdown_sink_rate_mps>3"))
            self.assertEqual(result["columns"][:4], ["touchdown_distance_past_transmitter_m", "touchdown_sink_rate_mps",
                                                     "touchdown_speed_mps", "touchdown_pitch_deg"])
            with h5py.File(archive, "r") as f:
                self.assertNotIn("analysis/dispersion", f)  # --no-write
                status = f["runs/status"][:]
                sink = f["results/landing/touchdown_sink_rate_mps"][:]
            c = result["groups"][0]["columns"][1]
            self.assertEqual(c["runs"], 24)
            self.assertEqual(c["values"] + c["failed"] + c["without_value"] + c["pending"], 24)
            self.assertEqual(c["failed"], int((status == 2).sum()))
            self.assertEqual(c["values"], int(((status == 1) & np.isfinite(sink)).sum()))
        finally:
            shutil.rmtree(directory, ignore_errors=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--gesweep", required=True)
    args, rest = parser.parse_known_args()
    GESWEEP = os.path.abspath(args.gesweep)
    unittest.main(argv=[sys.argv[0], *rest])
