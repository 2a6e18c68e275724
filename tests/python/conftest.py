"""Fixtures of the Python module's tests: the repository, the gesweep command (the oracle each function
is compared with) and the module, imported from build/python (PYTHONPATH, set by CTest)."""
import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
ANCE = ROOT / "studies" / "aircraft" / "ance.toml"
GESWEEP = os.environ.get("GESWEEP_BINARY", str(ROOT / "build" / "gesweep"))


def cli(*args, check=True):
    """Runs the gesweep command; returns (exit code, stdout, stderr)."""
    done = subprocess.run([GESWEEP, *map(str, args)], capture_output=True, text=True, timeout=120)
    if check and done.returncode != 0:
        raise AssertionError(f"gesweep {' '.join(map(str, args))}: exit {done.returncode}: {done.stderr}")
    return done.returncode, done.stdout, done.stderr


def cli_json(*args):
    return json.loads(cli(*args, "--format", "json")[1])


def cli_error(*args):
    """The one line the command prints for bad input (exit 2), without its 'gesweep: error: ' prefix."""
    code, _, err = cli(*args, check=False)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("gesweep: error: ")
    return lines[0][len("gesweep: error: "):]


@pytest.fixture(scope="session")
def gesweep():
    import gesweep as module
    return module


@pytest.fixture(scope="session")
def ance(gesweep):
    return gesweep.Aircraft.load(ANCE)
