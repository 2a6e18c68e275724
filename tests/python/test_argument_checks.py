"""Issue 26, item 7: every public function checks its arguments before any work, and a wrong one
raises gesweep.InputError naming it (never AttributeError, a bare TypeError, or a failure after the
work). Each function of gesweep.__all__ is called with a wrong type for each argument in turn, the
others right; the error must name the argument and come quickly (no sweep, no simulation run first).
The bounded-work refusal (item 5) of a 1e9-noise-sample run is checked here from Python too."""
import inspect
import time

import pytest

from conftest import ANCE

# A refusal before any work: import and start-up are done, so this is generous.
QUICK_S = 1.0
NOT_A_THING = object()


class Wrong:
    """A value of no type any argument takes (its repr names it in the message)."""

    def __repr__(self):
        return "<wrong>"


WRONG = Wrong()


def expect_input_error(gesweep, call, argument):
    started = time.monotonic()
    with pytest.raises(gesweep.InputError) as error:
        call()
    elapsed = time.monotonic() - started
    assert argument in str(error.value), f"{argument} not named in: {error.value}"
    assert elapsed < QUICK_S, f"refused after {elapsed:.2f} s: work was done before the check"
    assert "\n" not in str(error.value)
    return error.value


def model_option_cases(gesweep):
    """(keyword, a wrong value) for every model option: a number where a name belongs and the reverse."""
    wrong = {"h_derivatives": "yes", "cdh": 1.0, "interpolation": 2, "mass_kg": "heavy",
             "pitch_inertia_kgm2": "x", "cg_shift_over_chord": [1, 2], "CDo_scale": "x", "scale": 42}
    assert set(wrong) == {k for k, _, _ in gesweep.MODEL_OPTIONS}
    return list(wrong.items())


def wrong_setting(setting):
    """A wrong value for one setting of simulate_settings()/land_settings(): text for a number or a
    flag, a number for a name."""
    default = setting["default"]
    if isinstance(default, str):
        return 12.5
    return "not a number"


def test_every_public_function_is_covered(gesweep):
    covered = {"Aircraft", "modes", "boundary", "simulate", "land", "run", "open_archive", "list_products"}
    functions = {name for name in gesweep.__all__ if callable(getattr(gesweep, name))
                 and not inspect.isclass(getattr(gesweep, name)) or name == "Aircraft"}
    assert functions == covered


@pytest.mark.parametrize("where", [str(ANCE), ANCE, 42, None])
def test_a_path_or_anything_where_an_aircraft_belongs(gesweep, where):
    calls = [lambda: gesweep.modes(where, 5.0, 32.0), lambda: gesweep.boundary(where, 32.0),
             lambda: gesweep.simulate(where, 5.0, 32.0), lambda: gesweep.land(where)]
    for call in calls:
        error = expect_input_error(gesweep, call, "aircraft")
        assert "expected a gesweep.Aircraft" in str(error)
        if isinstance(where, (str, type(ANCE))):
            assert "gesweep.Aircraft.load(path)" in str(error)


def test_aircraft_load(gesweep, tmp_path):
    expect_input_error(gesweep, lambda: gesweep.Aircraft.load(42), "path")
    missing = tmp_path / "none.toml"
    error = expect_input_error(gesweep, lambda: gesweep.Aircraft.load(missing), str(missing))
    assert error.source == str(missing)


def test_modes_arguments(gesweep, ance):
    for argument, call in [
        ("height_m", lambda: gesweep.modes(ance, "low", 32.0)),
        ("speed_mps", lambda: gesweep.modes(ance, 5.0, WRONG)),
        ("speed_mps", lambda: gesweep.modes(ance, [1.0, 2.0, 3.0], [30.0, 31.0])),
        ("threads", lambda: gesweep.modes(ance, 5.0, 32.0, threads="two")),
        ("threads", lambda: gesweep.modes(ance, 5.0, 32.0, threads=2.5)),
        ("out", lambda: gesweep.modes(ance, 5.0, 32.0, out=42)),
    ]:
        expect_input_error(gesweep, call, argument)
    for key, value in model_option_cases(gesweep):
        expect_input_error(gesweep, lambda: gesweep.modes(ance, 5.0, 32.0, **{key: value}), key)


def test_boundary_arguments(gesweep, ance):
    for argument, call in [
        ("speed_mps", lambda: gesweep.boundary(ance, "fast")),
        ("speed_mps", lambda: gesweep.boundary(ance, WRONG)),
        ("method", lambda: gesweep.boundary(ance, 32.0, method=1)),
        ("sensitivities", lambda: gesweep.boundary(ance, 32.0, sensitivities="yes")),
    ]:
        expect_input_error(gesweep, call, argument)
    for key, value in model_option_cases(gesweep):
        expect_input_error(gesweep, lambda: gesweep.boundary(ance, 32.0, **{key: value}), key)


def test_simulate_arguments(gesweep, ance):
    for argument, call in [
        ("height_m", lambda: gesweep.simulate(ance, "low", 32.0)),
        ("speed_mps", lambda: gesweep.simulate(ance, 5.0, WRONG)),
        ("summary_only", lambda: gesweep.simulate(ance, 5.0, 32.0, summary_only="no")),
        ("output_dt_s", lambda: gesweep.simulate(ance, 5.0, 32.0, output_dt_s="fine")),
    ]:
        expect_input_error(gesweep, call, argument)
    for setting in gesweep._SIMULATE_SETTINGS:
        key = setting["key"]
        expect_input_error(gesweep, lambda: gesweep.simulate(ance, 5.0, 32.0, **{key: wrong_setting(setting)}), key)
    for key, value in model_option_cases(gesweep):
        expect_input_error(gesweep, lambda: gesweep.simulate(ance, 5.0, 32.0, **{key: value}), key)


def test_land_arguments(gesweep, ance):
    expect_input_error(gesweep, lambda: gesweep.land(ance, summary_only=1), "summary_only")
    for setting in gesweep._LAND_SETTINGS:
        key = setting["key"]
        expect_input_error(gesweep, lambda: gesweep.land(ance, **{key: wrong_setting(setting)}), key)
    for key, value in model_option_cases(gesweep):
        expect_input_error(gesweep, lambda: gesweep.land(ance, **{key: value}), key)


LONG_STUDY = f'''format_version = 1
name = "many_runs"
aircraft = "{ANCE}"
[analyses.modes]
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
linspace = [1.0, 50.0, 2000]
[[design.parameter]]
name = "speed_mps"
linspace = [25.0, 60.0, 200]
'''


def test_run_arguments_before_the_sweep(gesweep, tmp_path):
    """400,000 runs: a check made after the sweep would take far longer than QUICK_S."""
    study = tmp_path / "many.toml"
    study.write_text(LONG_STUDY)
    archive = tmp_path / "out.h5"
    for argument, call in [
        ("study_path", lambda: gesweep.run(42, archive)),
        ("archive_path", lambda: gesweep.run(study, WRONG)),
        ("threads", lambda: gesweep.run(study, archive, threads="all")),
        ("threads", lambda: gesweep.run(study, archive, threads=True)),
        ("progress", lambda: gesweep.run(study, archive, progress=42)),
        ("resume", lambda: gesweep.run(study, archive, resume="no")),
        ("force", lambda: gesweep.run(study, archive, force=1)),
        ("shard", lambda: gesweep.run(study, archive, shard=3)),
    ]:
        expect_input_error(gesweep, call, argument)
        assert not archive.exists() and not (tmp_path / "out.h5.partial").exists()


def test_archive_readers(gesweep, tmp_path):
    expect_input_error(gesweep, lambda: gesweep.open_archive(42), "path")
    expect_input_error(gesweep, lambda: gesweep.list_products(WRONG), "path")
    text = tmp_path / "notes.txt"
    text.write_text("not an archive\n")
    error = expect_input_error(gesweep, lambda: gesweep.open_archive(text), str(text))
    assert "not an archive" in str(error) or "HDF5" in str(error) or "cannot" in str(error)
    expect_input_error(gesweep, lambda: gesweep.open_archive(text, product=7), "product")


def test_a_run_of_1e9_noise_samples_is_refused_up_front(gesweep, ance):
    """Issue 26, item 5: 1e5 s at the finest sample interval would hold 1e9 noise samples (~32 GB)."""
    error = expect_input_error(
        gesweep, lambda: gesweep.simulate(ance, 100.0, 32.0, summary_only=True, input="none", duration_s=1e5,
                                          turbulence="dryden", turbulence_sample_interval_s=1e-4,
                                          wind_20ft_mps=-7.7),
        "turbulence_sample_interval_s")
    assert "expected at most 10000000 turbulence noise samples per run" in str(error)
    assert "1000000000 samples" in str(error)
    error = expect_input_error(
        gesweep, lambda: gesweep.land(ance, summary_only=True, time_limit_s=1e5, turbulence="dryden",
                                      turbulence_sample_interval_s=1e-4, wind_20ft_mps=-7.7),
        "turbulence_sample_interval_s")
    assert "1000000000 samples" in str(error)
