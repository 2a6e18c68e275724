"""gesweep.Aircraft, modes, boundary, simulate and land against the gesweep command's JSON output for
the same inputs (the same engine behind two front ends: the values must be equal, not close), and
checks of each result that do not go through the engine (NumPy on the returned eigenvalues)."""
import math

import numpy as np
import pytest

from conftest import ANCE, cli, cli_json


def cli_csv_header(*args):
    return cli(*args)[1].splitlines()[0].split(",")

SPEED = 32.0208  # the paper's speed, m/s


def nan_for_none(value):
    return math.nan if value is None else value


def test_aircraft_table_is_the_file(ance):
    import tomllib
    with open(ANCE, "rb") as f:
        data = tomllib.load(f)
    table = ance.table
    assert ance.name == data.get("name", ance.name)
    assert table.attrs["units"]["height_m"] == "m"
    heights = table["height_m"].to_numpy()
    assert np.isinf(heights[-1]) and np.all(np.diff(heights[:-1]) > 0)
    # Every tabulated column of the file, row by row (read here with tomllib, not by the engine).
    rows = data["table"]
    file_heights = rows["height_m"]
    np.testing.assert_array_equal(heights[:-1], file_heights)
    for name in ("CLo", "CMo", "CLalpha", "CMalpha", "CLh", "CMh"):
        np.testing.assert_array_equal(table[name].to_numpy()[:-1], rows[name])


def test_modes_equals_cli_at_table_heights(gesweep, ance):
    cli = cli_json("modes", "--aircraft", ANCE, "--speed-mps", SPEED, "--table-heights")
    heights = np.array([math.inf if r["height_m"] == "inf" else r["height_m"] for r in cli["rows"]])
    m = gesweep.modes(ance, heights, SPEED)
    assert m["eigenvalues"].shape == (len(heights), 5)
    for i, row in enumerate(cli["rows"]):
        expected = np.array([complex(re, im) for re, im in row["eigenvalues"]])
        np.testing.assert_array_equal(m["eigenvalues"][i], expected)
        assert m["stability_margin_per_s"][i] == row["stability_margin_per_s"]
        assert bool(m["stable"][i]) == row["stable"]
        assert gesweep.CLASSIFICATION_LEVELS[m["classification"][i]] == row["classification"]
        for mode in ("short_period", "phugoid", "height"):
            want = row["modes"][mode]
            assert m[f"{mode}/eigenvalue_re_per_s"][i] == want["re"]
            assert m[f"{mode}/eigenvalue_im_per_s"][i] == want["im"]
            for key in ("natural_frequency_radps", "damping_ratio", "period_s", "time_to_half_or_double_s"):
                assert m[f"{mode}/{key}"][i] == nan_for_none(want[key]) or (
                    want[key] is None and not np.isfinite(m[f"{mode}/{key}"][i])), (mode, key)
            assert bool(m[f"{mode}/oscillatory"][i]) == want["oscillatory"]


def test_modes_properties_follow_from_the_eigenvalues(gesweep, ance):
    """Independent of the engine's mode code: sigma is the largest real part of the non-neutral
    eigenvalues, the damping ratio -Re/|lambda|, computed here with NumPy."""
    h = np.geomspace(0.79, 14.0, 50)
    m = gesweep.modes(ance, h, SPEED)
    lam = m["eigenvalues"]
    neutral_tolerance = 1e-9  # the engine's neutral-root threshold, 1/s (docs/model.md section 6)
    re = np.where(np.abs(lam) <= neutral_tolerance, -np.inf, lam.real)
    np.testing.assert_array_equal(m["stability_margin_per_s"], re.max(axis=1))
    sp = lam[:, 0]
    np.testing.assert_allclose(m["short_period/damping_ratio"], -sp.real / np.abs(sp), rtol=1e-14)


def test_modes_broadcasts_and_keeps_shape(gesweep, ance):
    h = np.array([[1.0], [2.0], [4.0]])      # 3 x 1
    u = np.array([30.0, 40.0])               # 2
    m = gesweep.modes(ance, h, u, threads=2)
    assert m["eigenvalues"].shape == (3, 2, 5)
    assert m["stability_margin_per_s"].shape == (3, 2)
    single = gesweep.modes(ance, 2.0, 40.0)
    assert single["stability_margin_per_s"].shape == ()
    assert single["stability_margin_per_s"] == m["stability_margin_per_s"][1, 1]


def test_modes_out_writes_in_place_the_same_values(gesweep, ance):
    """out= (an earlier result) is written in place: the same arrays come back, holding what a fresh
    call returns, bit for bit, including at a new shape-compatible input."""
    h = np.geomspace(0.79, 14.0, 12).reshape(3, 4)
    first = gesweep.modes(ance, h, 30.0, threads=2)
    ids = {k: id(v) for k, v in first.items()}
    fresh = gesweep.modes(ance, h, 45.0, threads=2)
    again = gesweep.modes(ance, h, 45.0, threads=2, out=first)
    assert again is first and {k: id(v) for k, v in again.items()} == ids
    assert list(again) == list(fresh)
    for key in fresh:
        np.testing.assert_array_equal(again[key], fresh[key], err_msg=key)


def test_modes_new_arrays_are_independent(gesweep, ance):
    """The arrays of one call do not overlap: writing one leaves
    the others as they were."""
    m = gesweep.modes(ance, np.geomspace(0.79, 14.0, 7), 30.0)
    before = {k: v.copy() for k, v in m.items()}
    m["short_period/damping_ratio"][:] = -1.0
    for key, value in m.items():
        if key != "short_period/damping_ratio":
            np.testing.assert_array_equal(value, before[key], err_msg=key)
    keys = list(m)
    for i, a in enumerate(keys):
        for b in keys[i + 1:]:
            assert not np.shares_memory(m[a], m[b]), (a, b)


@pytest.mark.parametrize("change,message", [
    (lambda out: out.pop("stable"), "argument: out: expected an array 'stable'"),
    (lambda out: out.update(extra=np.zeros(3)), "expected exactly the keys of an earlier gesweep.modes result"),
    (lambda out: out.update(stable=np.zeros(3)), "out['stable'] = a float64 array of shape (3,): expected a writeable C-contiguous bool array of shape (3,)"),
    (lambda out: out.update(stable=np.zeros(4, dtype=bool)), "expected a C-contiguous array of shape (3,)"),
    (lambda out: out.update(eigenvalues=np.zeros((3, 5, 2))[:, :, 0]), "expected a C-contiguous array"),
    (lambda out: out["stable"].setflags(write=False), "out['stable'] = a read-only bool array of shape (3,): expected a writeable"),
])
def test_modes_out_refuses_what_it_cannot_write(gesweep, ance, change, message):
    out = gesweep.modes(ance, [1.0, 2.0, 3.0], 30.0)
    change(out)
    with pytest.raises(gesweep.InputError) as error:
        gesweep.modes(ance, [1.0, 2.0, 3.0], 30.0, out=out)
    assert message in str(error.value)
    assert "\n" not in str(error.value)


def test_modes_model_options_equal_cli(gesweep, ance):
    cli = cli_json("modes", "--aircraft", ANCE, "--speed-mps", 40, "--heights-m", "1.2,3",
                   "--no-h-derivatives", "--cdh", "zero", "--interpolation", "pchip")
    m = gesweep.modes(ance, [1.2, 3.0], 40.0, h_derivatives=False, cdh="zero", interpolation="pchip")
    np.testing.assert_array_equal(m["stability_margin_per_s"],
                                  [r["stability_margin_per_s"] for r in cli["rows"]])


@pytest.mark.parametrize("flags,kwargs", [((), {}), (("--no-h-derivatives",), {"h_derivatives": False})])
def test_boundary_equals_cli(gesweep, ance, flags, kwargs):
    cli = cli_json("boundary", "--aircraft", ANCE, "--speed-mps", SPEED, "--sensitivities", *flags)["boundaries"][0]
    b = gesweep.boundary(ance, SPEED, sensitivities=True, **kwargs)
    assert b["height_m"] == nan_for_none(cli["height_m"]) or (cli["height_m"] is None and math.isnan(b["height_m"]))
    assert b["certified"] == cli["certified"] and b["certificate"] == cli["certificate"]
    assert list(b["scanned_range_m"]) == cli["scanned_range_m"]
    assert b["other_crossings_m"] == cli["other_crossings_m"]
    assert len(b["crossings"]) == len(cli["crossings"])
    for mine, theirs in zip(b["crossings"], cli["crossings"]):
        assert mine["height_m"] == theirs["height_m"] and mine["kind"] == theirs["kind"]
        if "mode" in theirs:
            assert mine["mode"] == theirs["mode"]
            assert mine["eigenvalue"] == complex(*theirs["eigenvalue"])
    if cli["height_m"] is None:
        assert b["reason"] == cli["reason"]
        assert b["sensitivities"] == [] and b["sensitivities_reason"] == cli["sensitivities_reason"]
        return
    assert [s["parameter"] for s in b["sensitivities"]] == [s["parameter"] for s in cli["sensitivities"]]
    for mine, theirs in zip(b["sensitivities"], cli["sensitivities"]):
        assert mine["dH_dp"] == nan_for_none(theirs["dH_dp"]) and mine["p_dH_dp_m"] == theirs["p_dH_dp_m"]
    assert b["no_effect_parameters"] == cli["no_effect_parameters"]


def test_boundary_is_where_sigma_changes_sign(gesweep, ance):
    """H* against sigma from modes (a different code path: the eigen-analysis, not the Hurwitz
    criterion): unstable just below, stable just above."""
    step_m = 1e-6  # far above the finder's 1e-12 m refinement, far below the table spacing
    b = gesweep.boundary(ance, SPEED)
    sigma = gesweep.modes(ance, [b["height_m"] - step_m, b["height_m"] + step_m], SPEED)["stability_margin_per_s"]
    assert sigma[0] > 0 > sigma[1]
    assert gesweep.boundary(ance, [SPEED, 40.0])[0]["height_m"] == b["height_m"]


def test_simulate_equals_cli(gesweep, ance):
    cli = cli_json("simulate", "--aircraft", ANCE, "--height-m", 2.5935, "--speed-mps", SPEED, "--elevator-deg", 5,
                   "--pulse-s", 0.2, "--integrator", "rk4", "--dt-s", 0.015, "--duration-s", 20)
    r = gesweep.simulate(ance, 2.5935, SPEED, pulse_amplitude_deg=5, pulse_duration_s=0.2, integrator="rk4",
                         step_s=0.015, duration_s=20)
    for key, value in cli["summary"].items():
        assert r.summary[key] == (nan_for_none(value) if not isinstance(value, list)
                                  else [nan_for_none(v) for v in value]) or value is None, key
    for key, value in cli["run"].items():
        assert r.run[key] == nan_for_none(value) or value is None, key
    # The CSV's columns, in the CSV's order (the JSON object's keys come sorted).
    header = cli_csv_header("simulate", "--aircraft", ANCE, "--height-m", 2.5935, "--speed-mps", SPEED,
                            "--duration-s", 1)
    assert list(r.series.columns) == header
    for column, values in cli["series"].items():
        np.testing.assert_array_equal(r.series[column].to_numpy(), np.array(values, dtype=float), err_msg=column)


def test_simulate_frozen_response_is_linear(gesweep, ance):
    """A property the engine's code does not state: with the derivatives frozen, Eq. (1) is linear, so
    the response to twice the pulse is twice the response (superposition)."""
    base = dict(pulse_duration_s=0.2, integrator="rk4", step_s=0.01, duration_s=5, freeze_derivatives=True)
    one = gesweep.simulate(ance, 8.0, 40.0, pulse_amplitude_deg=1, **base).series
    two = gesweep.simulate(ance, 8.0, 40.0, pulse_amplitude_deg=2, **base).series
    linearity_tolerance = 1e-12  # relative: the frozen model is linear, only rounding differs
    scale = np.abs(one["delta_theta_rad"]).max()
    np.testing.assert_allclose(two["delta_theta_rad"], 2 * one["delta_theta_rad"], atol=linearity_tolerance * scale)


def test_simulate_summary_only_and_output_dt(gesweep, ance):
    r = gesweep.simulate(ance, 5.0, 40.0, summary_only=True, duration_s=2)
    assert r.series is None and r.summary["end_event"] == "time_limit"
    s = gesweep.simulate(ance, 5.0, 40.0, output_dt_s=0.5, duration_s=2).series
    np.testing.assert_allclose(s["time_s"], [0, 0.5, 1.0, 1.5, 2.0], atol=1e-12)


def test_land_equals_cli(gesweep, ance):
    cli = cli_json("land", "--aircraft", ANCE, "--summary-only", "--glide-slope-deg", 3)
    r = gesweep.land(ance, summary_only=True, glide_slope_deg=3)
    for key, value in cli["summary"].items():
        if key == "design":
            continue
        assert r.summary[key] == nan_for_none(value) or value is None, key
    design = cli["summary"]["design"]
    assert r.summary["design"]["gain"] == design["gain"]
    assert r.summary["design"]["closed_loop_eigenvalues_per_s"] == [complex(*z) for z in
                                                                      design["closed_loop_eigenvalues_per_s"]]
    series = gesweep.land(ance, glide_slope_deg=3).series
    assert series["phase"].iloc[-1] in ("flare", "glide_slope")
    assert {"time_s", "height_m", "elevator_rad", "pitch_rad"} <= set(series.columns)


def same_value(mine, theirs):
    """A value of the module against the command's JSON: null is NaN, a complex pair a complex, a dict
    key by key."""
    if isinstance(theirs, dict):
        return set(mine) == set(theirs) and all(same_value(mine[k], theirs[k]) for k in theirs)
    if theirs is None:
        return isinstance(mine, float) and math.isnan(mine)
    return mine == theirs


def test_land_run_equals_cli(gesweep, ance):
    """The settings flown (LandingConfig's description, the automatic ones as used) under the same keys,
    with the same values, as the command's JSON; the automatic flare time constant is Ho/(u0 sin γ)."""
    args = ("--glide-slope-deg", 3, "--plant-height-reference", "fixed", "--rtol", 1e-4, "--seed", 7)
    cli = cli_json("land", "--aircraft", ANCE, "--summary-only", *args)
    r = gesweep.land(ance, summary_only=True, glide_slope_deg=3, plant_height_reference="fixed",
                     relative_tolerance=1e-4, seed=7)
    assert set(r.run) == set(cli["run"])
    for key, value in cli["run"].items():
        assert same_value(r.run[key], value), key
    assert r.run["rtol"] == r.run["relative_tolerance"] == 1e-4
    assert r.run["seed"] == 7
    # The automatic τ (docs/landing.md): Ho/(u0 sin γ) with the defaults Ho = 10 m, u0 = 52.21 m/s.
    assert r.run["flare_time_constant_s"] == pytest.approx(10.0 / (52.21 * math.sin(math.radians(3))), rel=1e-12)


def test_land_in_a_mean_wind_equals_cli(gesweep, ance):
    """The disturbance keywords, from DisturbanceOptions' description as simulate's: a 5 m/s headwind
    without shear is u_g = -5 m/s at every sample, and no vertical air motion (docs/model.md §9)."""
    args = ("--wind-20ft-mps", -5, "--wind-shear", "none", "--output-dt-s", 2)
    cli = cli_json("land", "--aircraft", ANCE, *args)
    r = gesweep.land(ance, wind_20ft_mps=-5, wind_shear="none", output_interval_s=2)
    for key, value in cli["summary"].items():
        assert same_value(r.summary[key], value) if key != "design" else True, key
    assert r.summary["design"]["gain"] == cli["summary"]["design"]["gain"]
    assert set(r.series.columns) == set(cli["series"])
    for name, values in cli["series"].items():
        if name == "phase":
            assert list(r.series[name]) == values
        else:
            np.testing.assert_array_equal(r.series[name].to_numpy(), [nan_for_none(v) for v in values])
    np.testing.assert_array_equal(r.series["u_g_mps"].to_numpy(), -5.0)
    np.testing.assert_array_equal(r.series["w_g_mps"].to_numpy(), 0.0)
    assert "q_g_radps" not in r.series.columns  # only with the pitch-rate gust


def test_land_turbulence_replays_a_run(gesweep, ance):
    """seed and run_index select the noise RunNoise(seed, i), as the command's --seed and --run-index."""
    options = dict(summary_only=True, wind_20ft_mps=-6, turbulence="dryden", start_height_m=100)
    a = gesweep.land(ance, seed=3, run_index=2, **options)
    again = gesweep.land(ance, seed=3, run_index=2, **options)
    other = gesweep.land(ance, seed=3, run_index=1, **options)
    cli = cli_json("land", "--aircraft", ANCE, "--summary-only", "--wind-20ft-mps", -6, "--turbulence", "dryden",
                   "--start-height-m", 100, "--seed", 3, "--run-index", 2)
    assert a.summary["touchdown_time_s"] == again.summary["touchdown_time_s"] == cli["summary"]["touchdown_time_s"]
    assert a.summary["touchdown_sink_rate_mps"] != other.summary["touchdown_sink_rate_mps"]


def test_help_lists_every_option_with_its_default(gesweep):
    import pydoc
    text = pydoc.render_doc(gesweep.simulate, renderer=pydoc.plaintext)
    for s in gesweep._SIMULATE_SETTINGS:
        assert f"{s['key']} = {s['default']!r}" in text, s["key"]
    for key, default, _ in gesweep.MODEL_OPTIONS:
        assert f"{key} = {default!r}" in text
    assert "step_s = 0.015 [s]" in text
    land_text = pydoc.render_doc(gesweep.land, renderer=pydoc.plaintext)
    assert "glide_slope_deg = 2.5 [deg]" in land_text
    for s in gesweep._LAND_SETTINGS:
        assert f"{s['key']} = {s['default']!r}" in land_text, s["key"]
    for key in ("wind_20ft_mps", "turbulence", "gust_amplitude_mps", "seed", "run_index", "q_weights",
                "plant_height_reference", "turbulent_integrator", "design_h_derivatives"):
        assert key in {s["key"] for s in gesweep._LAND_SETTINGS}, key
