"""The records the command prints as JSON and the module returns as dicts are one description
(engine/analyses/records.h, issue 29): for each record, the command's JSON and the module's dict have
the same keys, at every depth, and the same values, exactly. The renderings differ only where the two
languages do: JSON's null is the module's nan (a number) or None (a missing part), a JSON pair
[re, im] is a complex, and a JSON pair [low, high] of scanned_range_m is a tuple."""
import math

import pytest

from conftest import ANCE, cli, cli_json

SPEED = 32.0208  # the paper's speed, m/s


def as_json(value):
    """A module value as the command's JSON would write it."""
    if isinstance(value, dict):
        return {key: as_json(v) for key, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [as_json(v) for v in value]
    if isinstance(value, complex):
        return [as_json(value.real), as_json(value.imag)]
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def assert_same_record(mine, theirs, path="record"):
    """Key sets equal at every depth and values equal exactly (not close): the same engine, two
    renderings. Says where the first difference is."""
    if isinstance(theirs, dict):
        assert isinstance(mine, dict), f"{path}: {mine!r} against an object"
        assert set(mine) == set(theirs), (f"{path}: keys only in the module {sorted(set(mine) - set(theirs))}, "
                                          f"only in the command {sorted(set(theirs) - set(mine))}")
        for key in theirs:
            assert_same_record(mine[key], theirs[key], f"{path}.{key}")
    elif isinstance(theirs, list):
        assert isinstance(mine, list) and len(mine) == len(theirs), f"{path}: {mine!r} against {theirs!r}"
        for i, (a, b) in enumerate(zip(mine, theirs)):
            assert_same_record(a, b, f"{path}[{i}]")
    else:
        assert type(mine) is type(theirs) or {type(mine), type(theirs)} <= {int, float}, \
            f"{path}: {mine!r} ({type(mine).__name__}) against {theirs!r} ({type(theirs).__name__})"
        assert mine == theirs, f"{path}: {mine!r} against {theirs!r}"


@pytest.mark.parametrize("flags,kwargs", [
    ((), {}),
    (("--no-h-derivatives",), {"h_derivatives": False}),   # no boundary: the reason, no sensitivities
    (("--method", "sampled"), {"method": "sampled"}),      # sign changes of sigma: crossings without a mode
])
def test_boundary_with_sensitivities_is_one_record(gesweep, ance, flags, kwargs):
    theirs = cli_json("boundary", "--aircraft", ANCE, "--speed-mps", SPEED, "--sensitivities", *flags)
    mine = gesweep.boundary(ance, SPEED, sensitivities=True, **kwargs)
    assert_same_record(as_json(mine), theirs["boundaries"][0], "boundary")
    assert isinstance(mine["scanned_range_m"], tuple)


def test_boundary_without_sensitivities_is_one_record(gesweep, ance):
    theirs = cli_json("boundary", "--aircraft", ANCE, "--speed-mps", 40.0)["boundaries"][0]
    mine = gesweep.boundary(ance, 40.0)
    assert "sensitivities" not in theirs
    assert_same_record(as_json(mine), theirs, "boundary")


@pytest.mark.parametrize("flags,kwargs", [
    (("--glide-slope-deg", 3), {"glide_slope_deg": 3}),
    (("--plant-height-reference", "fixed", "--rtol", 1e-4, "--seed", 7),
     {"plant_height_reference": "fixed", "relative_tolerance": 1e-4, "seed": 7}),
])
def test_landing_design_and_run_are_one_record(gesweep, ance, flags, kwargs):
    theirs = cli_json("land", "--aircraft", ANCE, "--summary-only", *flags)
    mine = gesweep.land(ance, summary_only=True, **kwargs)
    assert_same_record(as_json(mine.run), theirs["run"], "run")
    assert_same_record(as_json(mine.summary["design"]), theirs["summary"]["design"], "design")
    assert all(isinstance(z, complex) for z in mine.summary["design"]["closed_loop_eigenvalues_per_s"])


def frame_as_json(frame):
    """A module series (a DataFrame) as the command's JSON would write it: key -> list."""
    return {key: as_json(list(frame[key])) for key in frame.columns}


@pytest.mark.parametrize("flags,kwargs", [
    ((), {}),                                                               # still air: no air motion
    (("--wind-20ft-mps", -7.7, "--turbulence", "dryden", "--pitch-rate-gust", "--seed", 3),
     {"wind_20ft_mps": -7.7, "turbulence": "dryden", "pitch_rate_gust": True, "seed": 3}),
])
def test_open_loop_run_and_series_are_one_description(gesweep, ance, flags, kwargs):
    """simulate's CSV header, its JSON series and gesweep.simulate's series: the same quantities, in the
    same order (CSV and module), with the same values, exactly."""
    common = ("simulate", "--aircraft", ANCE, "--height-m", 2.5, "--speed-mps", SPEED, "--duration-s", 3,
              "--output-dt-s", 0.05, *flags)
    both = cli_json(*common)
    theirs = both["series"]
    header = cli(*common)[1].splitlines()[0].split(",")
    response = gesweep.simulate(ance, 2.5, SPEED, duration_s=3, output_dt_s=0.05, **kwargs)
    # The settings flown (OpenLoopRunRecord): the config, the model options, seed and run index.
    assert_same_record(as_json(response.run), both["run"], "run")
    assert {"h_derivatives", "cdh", "interpolation", "cg_shift_over_chord", "seed"} <= set(both["run"])
    mine = response.series
    assert list(mine.columns) == header
    assert_same_record(frame_as_json(mine), theirs, "series")
    # The archive's names: the state's components as the summary's final_* columns have them.
    assert {"delta_u_mps", "delta_w_mps", "pitch_rate_radps", "delta_theta_rad", "delta_h_m"} <= set(header)
    assert ("u_g_mps" in header) == ("q_g_radps" in header) == bool(flags)


def test_landing_series_is_one_description(gesweep, ance):
    """land's CSV header, its JSON series and gesweep.land's series: one description (SI, radians), the
    phase as its name."""
    common = ("land", "--aircraft", ANCE, "--start-height-m", 30, "--output-interval-s", 0.5)
    theirs = cli_json(*common)["series"]
    header = cli(*common)[1].splitlines()[0].split(",")
    mine = gesweep.land(ance, start_height_m=30, output_interval_s=0.5).series
    assert list(mine.columns) == header
    assert_same_record(frame_as_json(mine), theirs, "series")
    assert set(theirs["phase"]) == {"glide_slope", "flare"}
    assert {"pitch_rad", "elevator_rad", "pitch_rate_radps", "distance_past_transmitter_m"} <= set(header)
