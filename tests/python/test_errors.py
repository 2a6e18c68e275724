"""Bad input raises gesweep.InputError (a ValueError) with the gesweep command's line: the same text for
an input file; for an argument, the same expectation with the key the Python argument's name (the
command line names its flag) and the source 'argument' (the command line's is 'command line')."""
import pytest

from conftest import ANCE, cli_error


def python_wording(line, flag, key):
    """The command line's message as the module words it: 'command line: --flag' -> 'argument: key'."""
    return line.replace(f"command line: {flag}", f"argument: {key}")


@pytest.fixture
def bad_aircraft(tmp_path):
    text = ANCE.read_text()
    # Break the height column's order, as the README's example of an aircraft-file error.
    start = text.index("\nheight_m = [") + 1
    line_end = text.index("\n", start)
    line = text[start:line_end]
    values = line[line.index("[") + 1:line.rindex("]")].split(",")
    values[2], values[3] = values[3], values[2]
    path = tmp_path / "bad.toml"
    path.write_text(text[:start] + line[:line.index("[") + 1] + ",".join(values) + "]" + text[line_end:])
    return path


def test_bad_aircraft_file_same_line_as_cli(gesweep, bad_aircraft):
    line = cli_error("modes", "--aircraft", bad_aircraft, "--speed-mps", 30, "--table-heights")
    with pytest.raises(gesweep.InputError) as error:
        gesweep.Aircraft.load(bad_aircraft)
    assert str(error.value) == line
    assert isinstance(error.value, ValueError)
    assert error.value.source == str(bad_aircraft)


def test_missing_aircraft_file(gesweep, tmp_path):
    missing = tmp_path / "none.toml"
    line = cli_error("modes", "--aircraft", missing, "--speed-mps", 30, "--table-heights")
    with pytest.raises(gesweep.InputError) as error:
        gesweep.Aircraft.load(missing)
    assert str(error.value) == line


def test_height_below_the_wheels(gesweep, ance):
    line = cli_error("modes", "--aircraft", ANCE, "--speed-mps", 30, "--heights-m", "2,0.5")
    with pytest.raises(gesweep.InputError) as error:
        gesweep.modes(ance, [2.0, 0.5], 30.0)
    assert str(error.value) == python_wording(line, "--heights-m", "height_m")


def test_speed_outside_its_range(gesweep, ance):
    line = cli_error("boundary", "--aircraft", ANCE, "--speed-mps", 5000)
    with pytest.raises(gesweep.InputError) as error:
        gesweep.boundary(ance, 5000.0)
    assert str(error.value) == python_wording(line, "--speed-mps", "speed_mps")


def test_simulate_setting_outside_its_range(gesweep, ance):
    line = cli_error("simulate", "--aircraft", ANCE, "--height-m", 3, "--speed-mps", 32, "--duration-s", -1)
    with pytest.raises(gesweep.InputError) as error:
        gesweep.simulate(ance, 3.0, 32.0, duration_s=-1)
    assert str(error.value) == python_wording(line, "--duration-s", "duration_s")


def test_bad_choice_and_unknown_option(gesweep, ance):
    line = cli_error("modes", "--aircraft", ANCE, "--speed-mps", 30, "--heights-m", "2", "--cdh", "cubic")
    with pytest.raises(gesweep.InputError) as error:
        gesweep.modes(ance, 2.0, 30.0, cdh="cubic")
    assert str(error.value) == python_wording(line, "--cdh", "cdh")
    with pytest.raises(gesweep.InputError, match="argument: step = 0.01: unknown option"):
        gesweep.simulate(ance, 3.0, 32.0, step=0.01)
    with pytest.raises(gesweep.InputError, match="argument: integrator = 'euler': expected"):
        gesweep.simulate(ance, 3.0, 32.0, integrator="euler")


def test_bad_study_file_same_line_as_cli(gesweep, tmp_path):
    study = tmp_path / "bad.toml"
    study.write_text('format_version = 1\nname = "x"\naircraft = "%s"\n[analyses.modez]\n' % ANCE)
    line = cli_error("run", study, "-o", tmp_path / "out.h5")
    with pytest.raises(gesweep.InputError) as error:
        gesweep.run(study, tmp_path / "out.h5")
    assert str(error.value) == line
    assert not (tmp_path / "out.h5").exists()


def test_land_setting_outside_its_range_same_as_cli(gesweep, ance):
    line = cli_error("land", "--aircraft", ANCE, "--glide-slope-deg", 45)
    with pytest.raises(gesweep.InputError) as error:
        gesweep.land(ance, glide_slope_deg=45)
    assert str(error.value) == python_wording(line, "--glide-slope-deg", "glide_slope_deg")
    line = cli_error("land", "--aircraft", ANCE, "--turbulence", "foo")
    with pytest.raises(gesweep.InputError) as error:
        gesweep.land(ance, turbulence="foo")
    assert str(error.value) == python_wording(line, "--turbulence", "turbulence")


@pytest.mark.parametrize("call, message", [
    (lambda g, a: g.land(a, glide_slope_deg="steep"), "argument: glide_slope_deg = 'steep': expected a number"),
    (lambda g, a: g.land(a, summary_only="yes"), "argument: summary_only = 'yes': expected True or False"),
    (lambda g, a: g.land(a, wind_20ft="3"), "argument: wind_20ft = '3': unknown option; expected one of: "),
    (lambda g, a: g.land(a, seed=-1), "argument: seed = -1: expected a whole number in [0, 9007199254740992] written in digits"),
    (lambda g, a: g.land(a, seed="x"), "argument: seed = 'x': expected an int, a whole number in [0, 9007199254740992]"),
    (lambda g, a: g.land(a, q_weights=[1, 2]), "argument: q_weights = [1, 2]: expected a sequence of 9 numbers in the order delta_u, delta_w"),
    (lambda g, a: g.land(a, q_weights=[1] * 8 + ["x"]), "argument: q_weights.error_integral = 'x': expected a number"),
    (lambda g, a: g.land(a, plant_height_reference=1), "argument: plant_height_reference = 1: expected a string"),
    (lambda g, a: g.simulate(a, "3", 32.0), "argument: height_m = '3': expected a number"),
    (lambda g, a: g.simulate(a, 3.0, 32.0, output_dt_s="fine"), "argument: output_dt_s = 'fine': expected a number"),
    (lambda g, a: g.boundary(a, "fast"), "argument: speed_mps = 'fast': expected a number"),
    (lambda g, a: g.boundary(a, [30, "fast"]), "argument: speed_mps = [30, 'fast']: expected a number"),
    (lambda g, a: g.modes(a, "low", 30.0), "argument: height_m = 'low': expected a number"),
])
def test_wrongly_typed_argument_is_an_input_error(gesweep, ance, call, message):
    """A string where a number goes, an unknown keyword, a wrong list: InputError, one line naming the
    argument, the value and the expectation; also a TypeError, for code written against Python's own."""
    with pytest.raises(gesweep.InputError) as error:
        call(gesweep, ance)
    assert str(error.value).startswith(message), str(error.value)
    assert "\n" not in str(error.value)
    assert isinstance(error.value, ValueError) and isinstance(error.value, TypeError)
