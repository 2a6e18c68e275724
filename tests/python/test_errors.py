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
