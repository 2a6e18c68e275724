"""Issue 26, items 5 and 6: work bounded before it starts, and no foreign error text. Used by
run_bad_inputs.py, which runs each case through its check() (exit code, one printable line holding the
fragment, nothing left behind, no input changed).

- A turbulent run within every single limit that would hold 1e9 noise samples (duration 1e5 s at the
  finest sample interval, 1e-4 s: about 32 GB of noise table) is refused up front, naming the numbers:
  by a study (open loop and landing), by the dry run of that study, by `simulate` and `land` flags. Each
  runs under a 1 GB address-space limit and must end within WITHIN_S: the refusal comes before any
  table is built.
- `dispersion` with a tail probability below what the estimator supports (1e-17: 1 - p is 1 in double
  precision) is refused with its range, not with Boost's "erfc_inv ... Overflow Error".
- `run -o` into a read-only directory says it is read-only, not "not enough space" (a read-only tmpfs
  mounted when root; chmod 0555 otherwise; skipped when neither makes a directory unwritable).

The fragments are the engine's words, spelled out here from the limits (kMaximumNoiseSamplesPerRun =
1e7; the tail probabilities' range [1e-12, 0.5)), not taken from a run."""
import collections
import os
import pathlib
import subprocess
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent
ANCE = (ROOT.parent.parent / "studies" / "aircraft" / "ance.toml").resolve()

# The refusal is up front: start-up, the study read and checked; well under a second on an idle machine.
WITHIN_S = 1.0
# A case that built its noise table would need ~32 GB; under this limit it fails fast instead.
MEMORY_BYTES = 1 << 30

Case = collections.namedtuple("Case", "name args fragment kwargs")

NOISE = "expected at most 10000000 turbulence noise samples per run"
NOISE_NUMBERS = "100000 s / turbulence_sample_interval_s = 0.0001 s = 1000000000 samples (about 32 GB"


def open_loop_study():
    return (f'format_version = 1\nname = "noise_1e9"\naircraft = "{ANCE}"\n'
            "[analyses.open_loop]\ninput = \"none\"\nduration_s = 100000.0\nstep_s = 0.01\n"
            "turbulence_sample_interval_s = 0.0001\n"
            "[parameters]\nspeed_mps = 32.0208\nheight_m = 100.0\nturbulence = \"dryden\"\n"
            "wind_20ft_mps = -7.7\n")


def landing_study():
    return (f'format_version = 1\nname = "landing_noise_1e9"\naircraft = "{ANCE}"\n'
            "[analyses.landing]\ntime_limit_s = 100000.0\nturbulence_sample_interval_s = 0.0001\n"
            "[parameters]\nheight_m = 500.0\nspeed_mps = 52.21\nturbulence = \"dryden\"\n"
            "wind_20ft_mps = -7.7\n")


def modes_study():
    return (f'format_version = 1\nname = "eight_modes"\naircraft = "{ANCE}"\n[analyses.modes]\n'
            "[parameters]\nspeed_mps = 32.0\n[design]\nkind = \"grid\"\n[[design.parameter]]\n"
            'name = "height_m"\nlinspace = [1.0, 5.0, 8]\n')


def noise_cases(folder):
    """The 1e9-sample runs: study (open loop, landing, dry run) and flags (simulate, land)."""
    folder = pathlib.Path(folder)
    (folder / "noise.toml").write_text(open_loop_study())
    (folder / "landing_noise.toml").write_text(landing_study())
    bound = {"memory_bytes": MEMORY_BYTES, "timeout": 30, "within_s": WITHIN_S}
    flags = ["--turbulence", "dryden", "--turbulence-sample-interval-s", "1e-4", "--wind-20ft-mps", "-7.7"]
    return [
        Case("study: an open loop of 1e9 noise samples", ["run", str(folder / "noise.toml"), "-o", "{out}/out.h5"],
             NOISE, bound),
        Case("study: its dry run", ["run", str(folder / "noise.toml"), "--dry-run"], NOISE_NUMBERS, bound),
        Case("study: a landing of 1e9 noise samples",
             ["run", str(folder / "landing_noise.toml"), "-o", "{out}/out.h5"], NOISE, bound),
        Case("simulate: 1e9 noise samples by flags",
             ["simulate", "--aircraft", str(ANCE), "--height-m", "100", "--speed-mps", "32", "--input", "none",
              "--duration-s", "1e5", *flags, "--summary-only"],
             "command line: --turbulence-sample-interval-s = 0.0001: " + NOISE + ", but --duration-s = "
             + NOISE_NUMBERS.replace("turbulence_sample_interval_s", "--turbulence-sample-interval-s"), bound),
        Case("land: 1e9 noise samples by flags",
             ["land", "--aircraft", str(ANCE), "--time-limit-s", "1e5", *flags, "--summary-only"],
             "command line: --turbulence-sample-interval-s = 0.0001: " + NOISE, bound),
    ]


def dispersion_cases(gesweep, folder):
    """dispersion's tail probability below its range (and above), on a small archive of 8 modes runs."""
    folder = pathlib.Path(folder)
    (folder / "modes.toml").write_text(modes_study())
    archive = folder / "modes.h5"
    done = subprocess.run([gesweep, "run", str(folder / "modes.toml"), "-o", str(archive), "-q"],
                          capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        raise RuntimeError(f"the dispersion cases' archive: exit {done.returncode}: {done.stderr.strip()}")
    column = ["--columns", "stability_margin_per_s"]
    expected = "expected a probability in [1e-12, 0.5)"
    return [
        Case("dispersion --tail-probabilities 1e-17", ["dispersion", str(archive), *column,
                                                       "--tail-probabilities", "1e-17"],
             "command line: --tail-probabilities = 1e-17: " + expected, {"forbid": ("boost", "Overflow")}),
        Case("dispersion --tail-probabilities 1e-13 (with valid ones)",
             ["dispersion", str(archive), *column, "--tail-probabilities", "1e-3,1e-13", "--no-write"],
             "--tail-probabilities = 1e-13: " + expected, {}),
        Case("dispersion --confidence-level 0.9999999999999999",
             ["dispersion", str(archive), *column, "--confidence-level", "0.9999999999999999", "--no-write"],
             "--confidence-level = 1: expected a level in (0, 1 - 1e-12]", {}),
    ]


def read_only_directory(folder):
    """A directory that cannot be written, and how it was made; (None, why) when none can be made."""
    folder = pathlib.Path(folder)
    if os.geteuid() == 0:
        mount = folder / "read_only_mount"
        mount.mkdir()
        made = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(mount)],
                              capture_output=True, text=True)
        if made.returncode == 0:
            return mount, "it is on a read-only file system"
        return None, f"as root, a read-only tmpfs could not be mounted ({made.stderr.strip()})"
    plain = folder / "read_only"
    plain.mkdir()
    plain.chmod(0o555)
    if os.access(plain, os.W_OK):
        return None, "chmod 0555 left the directory writable"
    return plain, "it is read-only for this user (permission denied)"


def release_read_only(directory):
    if directory is None:
        return
    if directory.name == "read_only_mount":
        subprocess.run(["umount", str(directory)], capture_output=True)
    else:
        directory.chmod(0o755)


def read_only_case(folder, directory, words):
    """`run -o` into the read-only directory: the modes study of dispersion_cases (made first)."""
    study = pathlib.Path(folder) / "modes.toml"
    if not study.exists():
        study.write_text(modes_study())
    return Case("run -o into a read-only directory", ["run", str(study), "-o", str(directory / "out.h5")],
                f"cannot write in the directory {directory}: {words}", {"forbid": ("not enough space",)})


def constant_column_problems(gesweep, folder):
    """`dispersion` of a column whose every value is the same (modes' height_over_span of one height
    repeated): exit 0, the column stated as "no spread" (table, JSON and the archive's no_spread), no
    tail fit; returns the problems found."""
    import json
    folder = pathlib.Path(folder)
    (folder / "constant.toml").write_text(
        f'format_version = 1\nname = "constant"\naircraft = "{ANCE}"\n[analyses.modes]\n'
        "[parameters]\nheight_m = 3.0\n[design]\nkind = \"grid\"\n[[design.parameter]]\n"
        'name = "speed_mps"\nvalues = [30.0, 31.0, 32.0, 33.0, 34.0, 35.0]\n')
    archive = folder / "constant.h5"
    problems = []
    done = subprocess.run([gesweep, "run", str(folder / "constant.toml"), "-o", str(archive), "-q"],
                          capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        return [f"constant column: the archive: exit {done.returncode}: {done.stderr.strip()[:300]}"]
    table = subprocess.run([gesweep, "dispersion", str(archive), "--columns", "height_over_span"],
                           capture_output=True, text=True, timeout=60)
    if table.returncode != 0 or table.stderr.strip():
        problems.append(f"dispersion of a constant column: exit {table.returncode}: {table.stderr.strip()[:300]}")
    elif "no spread: all 6 values are" not in table.stdout:
        problems.append(f"dispersion of a constant column does not say 'no spread': {table.stdout[-600:]}")
    as_json = subprocess.run([gesweep, "dispersion", str(archive), "--columns", "height_over_span", "--format",
                              "json", "--no-write"], capture_output=True, text=True, timeout=60)
    if as_json.returncode != 0:
        problems.append(f"dispersion --format json of a constant column: exit {as_json.returncode}: "
                        f"{as_json.stderr.strip()[:300]}")
    else:
        column = json.loads(as_json.stdout)["groups"][0]["columns"][0]
        # 3 m over ANCE's span, the same for every run: a spread of exactly 0, no fit.
        if column.get("no_spread") is not True or column["standard_deviation"] != 0.0:
            problems.append(f"dispersion JSON of a constant column: no_spread {column.get('no_spread')!r}, "
                            f"standard_deviation {column['standard_deviation']!r}")
        if any(f["location"] is not None for f in column["fits"]):
            problems.append(f"dispersion JSON of a constant column holds a fit: {column['fits']}")
    try:
        import h5py
        with h5py.File(archive, "r") as f:
            stored = f["analysis/dispersion/no_spread"][...]
            if stored.tolist() != [[1]]:
                problems.append(f"/analysis/dispersion/no_spread of a constant column: {stored.tolist()}")
    except (OSError, KeyError) as error:
        problems.append(f"/analysis/dispersion/no_spread not readable: {error}")
    return problems


def with_folder(function):
    with tempfile.TemporaryDirectory() as folder:
        return function(folder)
