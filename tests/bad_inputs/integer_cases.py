"""Seeds, run indices and counts are whole numbers, parsed exactly (issue 26, item 3): every entry point
refuses a value past the limits table's range, a sign, a fraction or an exponent with one line naming
the range, where the engine before this change wrapped (`--seed -1` flew seed 2^64 - 1), clamped
(`--seed 2^64+1`), rounded through a double (a study's `seed = 2^53 + 1` flew 2^53) or took a seed
beyond the 2^53 a study refuses (`land --seed 2^53 + 1`).

cases(folder) returns Case(name, args, fragment) for run_bad_inputs.py's check(): the expected exit
code is 2, the fragment is spelled out here from the limits table's words (docs/limits.md), not taken
from a run. `folder` receives the study files and design CSVs the cases need.

Decided (docs/limits.md, "Whole numbers"): only digits -- no sign (`+5` too), no fraction (`5.0`
too: a TOML float may already have been rounded by the reader), no exponent (`1e3` too) -- in flags,
study files (a TOML integer) and design CSVs; Python takes an int (tests/python/test_exact_integers.py).
"""
import collections
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent
ANCE = (ROOT.parent.parent / "studies" / "aircraft" / "ance.toml").resolve()

Case = collections.namedtuple("Case", "name args fragment")

TWO_53 = 2**53
SEED_RANGE = "expected a whole number in [0, 9007199254740992]"
DIGITS = " written in digits"
# Past each end, and not a whole number written in digits.
BEYOND = ["-1", str(TWO_53 + 1), str(2**64), str(2**64 + 1), str(10**30)]
NOT_DIGITS = ["1.5", "1e3", "+5", "5.0", "0x10", " 7"]

SIMULATE = ["simulate", "--aircraft", str(ANCE), "--height-m", "40", "--speed-mps", "52.21", "--duration-s",
            "1", "--summary-only"]
LAND = ["land", "--aircraft", str(ANCE), "--summary-only"]


def flag_cases(folder):
    study = folder / "flag_study.toml"
    study.write_text(f'format_version = 1\nname = "f"\naircraft = "{ANCE}"\n[analyses.modes]\n'
                     "[parameters]\nspeed_mps = 32.0\nheight_m = 3.0\n")
    commands = [
        ("simulate --seed", SIMULATE, "--seed", SEED_RANGE),
        ("simulate --run-index", SIMULATE, "--run-index", SEED_RANGE),
        ("land --seed", LAND, "--seed", SEED_RANGE),
        ("land --run-index", LAND, "--run-index", SEED_RANGE),
        # The bootstrap's seed: the same range (the archive stores it as a 64-bit signed integer).
        ("sensitivity --seed", ["sensitivity", str(ANCE), "--output", "x"], "--seed", SEED_RANGE),
    ]
    for name, base, flag, expected in commands:
        for value in BEYOND:
            yield Case(f"{name} {value}", [*base, flag, value], f"command line: {flag} = {value}: {expected}")
        for value in NOT_DIGITS:
            yield Case(f"{name} {value!r}", [*base, flag, value],
                       f"command line: {flag} = {value}: {expected}{DIGITS}")
    # Counts: their own whole entries.
    counts = [
        ("sensitivity --bootstrap", ["sensitivity", str(ANCE), "--output", "x"], "--bootstrap",
         "expected a whole number in [0, 1000000]", ["-1", "1000001", str(2**31), "2.5"]),
        ("run --threads", ["run", str(study), "-o", str(folder / "never.h5")], "--threads",
         "expected a whole number in [1, 4096]", ["0", "4097", "-1", str(2**32 + 1), "1.5"]),
    ]
    for name, base, flag, expected, values in counts:
        for value in values:
            yield Case(f"{name} {value}", [*base, flag, value], f"command line: {flag} = {value}: {expected}")


def study_text(parameters="", design=""):
    return (f'format_version = 1\nname = "integers"\naircraft = "{ANCE}"\n[analyses.open_loop]\n'
            f'duration_s = 1.0\n[parameters]\nheight_m = 40.0\nspeed_mps = 52.21\nturbulence = "dryden"\n'
            f"{parameters}{design}")


def grid(axis):
    return f'[design]\nkind = "grid"\n[[design.parameter]]\nname = "seed"\n{axis}\n'


def study_cases(folder):
    out = folder / "never.h5"
    made = []

    def case(name, text, fragment, csv=None):
        path = folder / f"study_{len(made)}.toml"
        path.write_text(text)
        if csv is not None:
            (folder / f"design_{len(made)}.csv").write_text(csv)
        made.append(path)
        return Case(f"study: {name}", ["run", str(path), "-o", str(out)], fragment)

    # [parameters] seed: a TOML integer beyond the range (2^53 + 1 was read as 2^53 through a double).
    for value in ["-1", str(TWO_53 + 1), str(TWO_53 + 2), str(2**63 - 1)]:
        yield case(f"seed = {value}", study_text(f"seed = {value}\n"),
                   f"parameters.seed = {value}: {SEED_RANGE}")
    yield case("seed = 2^64", study_text(f"seed = {2**64}\n"), f"'{2**64}' is not representable in 64 bits")
    for value in ["1.5", "1e3", "5.0", "9007199254740993.0"]:
        yield case(f"seed = {value}", study_text(f"seed = {value}\n"),
                   f"{SEED_RANGE} written as an integer")
    # A grid axis of seeds: listed values as [parameters]; a linspace whose spacing is not whole (and
    # 0, 22, 23 is whole: it used to give 14.999999999999998 for the 16th seed, flown as 14).
    yield case("grid values [..., 2^53 + 1]", study_text(design=grid(f"values = [1, {TWO_53 + 1}]")),
               f"design.parameter[0].values[1] = {TWO_53 + 1}: {SEED_RANGE}")
    yield case("grid values [2.0]", study_text(design=grid("values = [1, 2.0]")),
               f"{SEED_RANGE} written as an integer")
    yield case("grid linspace [0, 10, 4]", study_text(design=grid("linspace = [0, 10, 4]")),
               "expected whole values for seed: linspace = [start, stop, n] with stop - start a multiple of n - 1")
    yield case("grid logspace [1, 1000, 4]", study_text(design=grid("logspace = [1, 1000, 4]")),
               "expected whole values for seed")
    yield case("grid linspace to 2^53 + 2", study_text(design=grid(f"linspace = [0, {TWO_53 + 2}, 3]")),
               SEED_RANGE)
    # A list design's rows and a design CSV's cells: the CSV's text digits exactly (strtod rounded).
    yield case("list row seed 2^53 + 1",
               study_text(design=f'[design]\nkind = "list"\ncolumns = ["seed"]\nrows = [[{TWO_53 + 1}]]\n'),
               f"design.rows[0][0] = {TWO_53 + 1}: {SEED_RANGE}")
    for value in [str(TWO_53 + 1), "-1", "1.5", "1e3", str(2**64 + 1)]:
        index = len(made)
        yield case(f"design CSV seed {value}",
                   study_text(design=f'[design]\nkind = "list"\ncsv = "design_{index}.csv"\n'),
                   f'seed = "{value}": {SEED_RANGE}', csv=f"seed\n3\n{value}\n")
    # A design's own seed (lhs, morris, monte_carlo): a TOML integer, within the same range.
    for value in ["-1", str(TWO_53 + 1)]:
        yield case(f"monte_carlo design seed = {value}",
                   study_text(design=f'[design]\nkind = "monte_carlo"\nsamples = 4\nseed = {value}\n'
                                     '[[design.parameter]]\nname = "wind_20ft_mps"\nuniform = [-5.0, 5.0]\n'),
                   f"design.seed = {value}: {SEED_RANGE}")
    # Sampled over a range, a seed would take fractions (and be truncated): refused.
    yield case("monte_carlo uniform seed",
               study_text(design='[design]\nkind = "monte_carlo"\nsamples = 4\nseed = 1\n'
                                 '[[design.parameter]]\nname = "seed"\nuniform = [0.0, 100.0]\n'),
               "a continuous distribution needs a real-valued parameter")
    yield case("lhs over seed",
               study_text(design='[design]\nkind = "lhs"\nsamples = 4\nseed = 1\n'
                                 '[[design.parameter]]\nname = "seed"\nuniform = [0.0, 100.0]\n'),
               "a range is sampled with fractions, but seed takes " + SEED_RANGE[len("expected "):])


def cases(folder):
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return [*flag_cases(folder), *study_cases(folder)]
