"""Seeds and run indices are whole numbers, taken exactly (issue 26, item 3): Python's simulate and land
take an int (or a NumPy integer) in the limits table's range [0, 2^53], as the command's --seed and
--run-index do, and refuse the rest with the command's expectation; a run of a stored sweep replays
from Python with its stored seed and run index, to the bit, seeds at the top of the range included."""
import h5py
import numpy as np
import pytest

from conftest import ANCE, cli, cli_error

TWO_53 = 2**53
RANGE = "expected a whole number in [0, 9007199254740992]"
SIMULATE = dict(summary_only=True, duration_s=1.0, turbulence="dryden", wind_20ft_mps=-7.717)


@pytest.mark.parametrize("key", ["seed", "run_index"])
@pytest.mark.parametrize("value", [0, 1, TWO_53 - 1, TWO_53, np.int64(TWO_53), np.uint64(TWO_53)])
def test_edges_accepted(gesweep, ance, key, value):
    r = gesweep.simulate(ance, 40.0, 52.21, **SIMULATE, **{key: value})
    assert r.run[key] == int(value)
    assert gesweep.land(ance, summary_only=True, time_limit_s=1.0, **{key: value}).run[key] == int(value)


@pytest.mark.parametrize("key", ["seed", "run_index"])
@pytest.mark.parametrize("value", [-1, TWO_53 + 1, 2**64, 2**64 + 1, 10**30])
def test_beyond_the_range_refused_as_the_command_does(gesweep, ance, key, value):
    flag = "--" + key.replace("_", "-")
    line = cli_error("simulate", "--aircraft", ANCE, "--height-m", 40, "--speed-mps", 52.21, "--summary-only",
                     flag, value)
    assert line.startswith(f"command line: {flag} = {value}: {RANGE}"), line
    expected = line.split(": ", 2)[2]
    for call in (lambda: gesweep.simulate(ance, 40.0, 52.21, **SIMULATE, **{key: value}),
                 lambda: gesweep.land(ance, summary_only=True, **{key: value})):
        with pytest.raises(gesweep.InputError) as error:
            call()
        assert str(error.value) == f"argument: {key} = {value}: {expected}"


@pytest.mark.parametrize("key", ["seed", "run_index"])
@pytest.mark.parametrize("value", [1.5, 1e3, 5.0, float("nan"), True, "5", np.float64(3.0), np.bool_(True)])
def test_not_an_int_refused(gesweep, ance, key, value):
    for call in (lambda: gesweep.simulate(ance, 40.0, 52.21, **SIMULATE, **{key: value}),
                 lambda: gesweep.land(ance, summary_only=True, **{key: value})):
        with pytest.raises(gesweep.InputError, match=rf"^argument: {key} = .*: expected an int, a whole number in "
                                                     r"\[0, 9007199254740992\]"):
            call()


def test_replay_from_python_equals_the_stored_row(gesweep, ance, tmp_path):
    """A turbulent sweep over seeds at the top of the range and a linspace of seeds; each run flown
    again by gesweep.simulate with its stored seed (exact: at most 2^53) and run index."""
    study = tmp_path / "replay.toml"
    study.write_text(f'format_version = 1\nname = "py_replay"\naircraft = "{ANCE}"\n[analyses.open_loop]\n'
                     'duration_s = 4.0\nintegrator = "rk4"\nstep_s = 0.01\ninput = "none"\n[parameters]\n'
                     'height_m = 40.0\nspeed_mps = 52.21\nturbulence = "dryden"\nwind_20ft_mps = -7.717\n'
                     '[design]\nkind = "grid"\n[[design.parameter]]\nname = "seed"\n'
                     f"values = [{TWO_53}, {TWO_53 - 1}, 15, 14]\n")
    archive = tmp_path / "replay.h5"
    cli("run", study, "-o", archive, "--quiet")
    with h5py.File(archive, "r") as f:
        index, seed = f["runs/index"][:], f["design/seed"][:]
        height = f["results/open_loop/final_height_m"][:]
    assert list(seed) == [2.0**53, 2.0**53 - 1, 15.0, 14.0]
    for row in range(len(index)):
        r = gesweep.simulate(ance, 40.0, 52.21, summary_only=True, duration_s=4.0, integrator="rk4", step_s=0.01,
                             input="none", turbulence="dryden", wind_20ft_mps=-7.717, seed=int(seed[row]),
                             run_index=int(index[row]))
        assert r.summary["final_height_m"] == height[row], row
    # Another seed, same run index: another flight (the comparison can fail).
    r = gesweep.simulate(ance, 40.0, 52.21, summary_only=True, duration_s=4.0, integrator="rk4", step_s=0.01,
                         input="none", turbulence="dryden", wind_20ft_mps=-7.717, seed=TWO_53 - 2,
                         run_index=int(index[0]))
    assert r.summary["final_height_m"] != height[0]


@pytest.mark.parametrize("key,flag,call", [
    ("time_limit_s", "--time-limit-s", "land"), ("design_height_m", "--design-height-m", "land"),
    ("flare_time_constant_s", "--flare-time-constant-s", "land"),
    ("turbulence_sigma_w_mps", "--turbulence-sigma-w-mps", "land"),
    ("turbulence_sigma_w_mps", "--turbulence-sigma-w-mps", "simulate"),
])
def test_nan_is_never_an_input(gesweep, ance, key, flag, call):
    """An automatic setting is automatic when left out; NaN is refused, by the flag and the keyword alike
    (docs/limits.md, "NaN is never an input"). Before: Python took NaN, the flags mostly refused it."""
    base = (["--height-m", 40, "--speed-mps", 52.21] if call == "simulate" else [])
    line = cli_error(call, "--aircraft", ANCE, *base, "--summary-only", flag, "nan")
    assert line.startswith(f"command line: {flag} = nan: expected a number in "), line
    expected = line.split(": ", 2)[2]
    args = (40.0, 52.21) if call == "simulate" else ()
    with pytest.raises(gesweep.InputError) as error:
        getattr(gesweep, call)(ance, *args, summary_only=True, **{key: float("nan")})
    assert str(error.value).startswith(f"argument: {key} = nan: {expected}"), str(error.value)
    # Left out, it is automatic: it flies (land's run shows the value used).
    r = getattr(gesweep, call)(ance, *args, summary_only=True, **({"duration_s": 1.0} if call == "simulate" else {}))
    if call == "land":
        assert r.run[key] == r.run[key], key  # a number, not NaN
