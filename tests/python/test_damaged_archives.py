"""gesweep.open_archive of the eight files on which libhdf5 1.10.8 itself hangs or crashes
(tests/fuzz/hdf5_defects; docs/reliability.md 11.4): gesweep.InputError naming the file, the same
line as `gesweep query FILE --describe`, within 5 s each, the file's bytes unchanged, and the Python
process alive (before this change it hung or died with the file)."""
import sys
import time

import pytest

from conftest import ROOT, cli_error

sys.path.insert(0, str(ROOT / "tests" / "bad_inputs"))
import damaged_cases  # noqa: E402


@pytest.fixture(scope="module")
def defects(tmp_path_factory):
    return damaged_cases.defect_files(tmp_path_factory.mktemp("defects"))


@pytest.mark.parametrize("name", damaged_cases.DEFECT_NAMES)
def test_open_archive_refuses_a_file_that_breaks_libhdf5(gesweep, defects, name):
    path = defects[name]
    before = damaged_cases.sha256(path)
    start = time.monotonic()
    with pytest.raises(gesweep.InputError) as raised:
        gesweep.open_archive(path)
    seconds = time.monotonic() - start
    assert seconds < damaged_cases.SECONDS, f"{name}: {seconds:.1f} s"
    text = str(raised.value)
    assert text.startswith(f"{path}: "), text
    assert "\n" not in text
    assert raised.value.source == str(path)
    if name in damaged_cases.ALWAYS_BREAKS:
        assert text.startswith(f"{path}: libhdf5 ") and damaged_cases.DAMAGED in text, text
    assert damaged_cases.sha256(path) == before, f"{name}: changed"
    # The command refuses it too (in the same words, unless libhdf5's bad free or overflowing read
    # fails cleanly in one process and by a signal in the other: heap layouts differ).
    line = cli_error("query", path, "--describe")
    assert line.startswith(f"{path}: "), line
    assert damaged_cases.sha256(path) == before
