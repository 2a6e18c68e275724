"""gesweep.open_archive refuses exactly what the gesweep command refuses (issue 26): every broken
virtual archive of tests/bad_inputs/shard_cases.py raises gesweep.InputError with the command's own
line; a shard deleted is that refusal, not half the runs read as pending; a text file and a truncated
archive raise InputError naming the file and why; an archive merged before identities is read with an
ArchiveNote warning, the command's note; HDF5_VDS_PREFIX is honoured, the file found there checked."""
import os
import pathlib
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest

from conftest import GESWEEP, ROOT, cli, cli_error

sys.path.insert(0, str(ROOT / "tests" / "bad_inputs"))
import shard_cases  # noqa: E402


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    return shard_cases.make(GESWEEP, tmp_path_factory.mktemp("shards"))


def test_open_archive_refuses_every_broken_virtual_archive_in_the_commands_words(gesweep, cases):
    assert len(cases) >= 11
    for case in cases:
        line = cli_error("query", case.archive)
        assert case.fragment in line, (case.name, line)
        with pytest.raises(gesweep.InputError) as raised:
            gesweep.open_archive(case.archive)
        assert str(raised.value) == line, case.name
        # The archive whose source failed: the one opened, or (a cycle) the one read through it.
        assert raised.value.source in (case.archive, str(pathlib.Path(case.archive).parent / "merged.h5")), case.name
        with pytest.raises(gesweep.InputError) as listed:
            gesweep.list_products(case.archive)
        assert str(listed.value) == line, case.name


def test_a_deleted_shard_is_refused_not_read_as_pending_runs(gesweep, cases):
    deleted = next(c for c in cases if c.name == "a shard deleted")
    with pytest.raises(gesweep.InputError, match="s1.h5 is missing"):
        gesweep.open_archive(deleted.archive)


def test_the_intact_merge_reads_as_its_shards(gesweep, cases):
    base = pathlib.Path(cases[0].archive).parent.parent / "base"
    ds = gesweep.open_archive(base / "merged.h5")
    shard0, shard1 = gesweep.open_archive(base / "s0.h5"), gesweep.open_archive(base / "s1.h5")
    np.testing.assert_array_equal(ds.stability_margin_per_s.values,
                                  np.concatenate([shard0.stability_margin_per_s.values,
                                                  shard1.stability_margin_per_s.values]))
    assert len(ds.attrs["archive_id"]) == 32


def test_a_text_file_and_a_truncated_archive_name_the_file_and_why(gesweep, tmp_path):
    text = tmp_path / "notes.h5"
    text.write_text("a text file, not an archive\n")
    with pytest.raises(gesweep.InputError) as raised:
        gesweep.open_archive(text)
    assert str(raised.value) == cli_error("query", text)
    assert str(raised.value).startswith(f"{text}: ") and "not an HDF5 file" in str(raised.value)
    archive = tmp_path / "whole.h5"
    cli("run", ROOT / "tests" / "bad_inputs" / "old_archives" / "study.toml", "-o", archive, "-q")
    truncated = tmp_path / "truncated.h5"
    truncated.write_bytes(archive.read_bytes()[: archive.stat().st_size // 2])
    with pytest.raises(gesweep.InputError) as raised:
        gesweep.open_archive(truncated)
    assert str(raised.value).startswith(f"{truncated}: "), str(raised.value)
    assert str(raised.value) == cli_error("query", truncated).replace(
        f"gesweep run STUDY -o {truncated} --resume", f'gesweep.run(study, "{truncated}", resume=True)')
    with pytest.raises(gesweep.InputError, match="expected a path"):
        gesweep.open_archive(42)


def test_an_archive_merged_before_identities_is_read_with_the_commands_note(gesweep, tmp_path):
    old = tmp_path / "old"
    shutil.copytree(ROOT / "tests" / "bad_inputs" / "old_archives", old)
    code, _, err = cli("query", old / "merged.h5")
    notes = [line for line in err.splitlines() if line.startswith("gesweep: note: ")]
    assert code == 0 and len(notes) == 1, err
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = gesweep.open_archive(old / "merged.h5")
    assert [str(w.message) for w in caught if issubclass(w.category, gesweep.ArchiveNote)] == \
        [notes[0][len("gesweep: note: "):]]
    assert int((ds.status == 1).sum()) == 8


def test_hdf5_vds_prefix_is_honoured_and_the_file_found_there_checked(cases, tmp_path):
    """In a fresh interpreter (HDF5 reads the variable when it starts): the merge's shard moved to the
    prefix's directory reads as before; another shard's file there is refused, naming it."""
    base = pathlib.Path(cases[0].archive).parent.parent / "base"
    here = tmp_path / "here"
    shutil.copytree(base, here)
    reference = subprocess.run([GESWEEP, "query", str(here / "merged.h5")], capture_output=True, text=True).stdout
    prefix = tmp_path / "prefix"
    prefix.mkdir()
    os.rename(here / "s0.h5", prefix / "s0.h5")
    script = ("import sys, gesweep\n"
              "try:\n    ds = gesweep.open_archive(sys.argv[1])\n"
              "    print(float(ds.stability_margin_per_s.values[0]))\n"
              "except gesweep.InputError as e:\n    print('refused:', e)\n")
    env = dict(os.environ, HDF5_VDS_PREFIX=str(prefix))

    def python():
        return subprocess.run([sys.executable, "-c", script, str(here / "merged.h5")], env=env, capture_output=True,
                              text=True, timeout=120).stdout.strip()

    first = gesweep_value(base / "s0.h5")
    assert python() == repr(first)
    moved = subprocess.run([GESWEEP, "query", str(here / "merged.h5")], env=env, capture_output=True, text=True)
    assert moved.returncode == 0 and moved.stdout.replace(str(here), "") == reference.replace(str(here), ""), \
        moved.stderr
    shutil.copyfile(base / "s1.h5", prefix / "s0.h5")
    out = python()
    assert out.startswith("refused: ") and f"shard file {prefix / 's0.h5'} holds runs 4..7" in out, out
    line = subprocess.run([GESWEEP, "query", str(here / "merged.h5")], env=env, capture_output=True, text=True)
    assert line.returncode == 2 and out == "refused: " + line.stderr.strip()[len("gesweep: error: "):]


def gesweep_value(archive):
    """The first run's margin as h5py reads the shard itself (the oracle: no virtual dataset in between)."""
    import h5py
    with h5py.File(archive, "r") as f:
        return float(f["results/modes/stability_margin_per_s"][0])
