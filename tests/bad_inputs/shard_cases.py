"""The ways a virtual archive's shard files go wrong (issue 26, item 1), made for real: shards run by
the gesweep under test, merged, then replaced, swapped, copied over, deleted, moved, linked to the
merge, taken from another study, re-run; and a cycle of virtual archives made from the archives of
tests/bad_inputs/old_archives (written before identities, by the engine whose readers died with
SIGSEGV on it). Used by run_bad_inputs.py (every reader command must refuse each one with one line)
and by tests/python/test_shard_identity.py (gesweep.open_archive must refuse each one in the same
words).

make(gesweep, folder) builds every case in its own subfolder of `folder` and returns a list of Case:
`archive` is what a reader is given, `fragment` what its one line must contain, `protect` the files
that must be left as they are. The fragments are the reader's words, spelled out here from what each
case did (not taken from a run of the reader)."""
import collections
import os
import pathlib
import shutil
import subprocess

ROOT = pathlib.Path(__file__).resolve().parent
ANCE = (ROOT.parent.parent / "studies" / "aircraft" / "ance.toml").resolve()
OLD_ARCHIVES = ROOT / "old_archives"

Case = collections.namedtuple("Case", "name archive fragment protect")

# The reader commands, each given the archive as {a} and a scratch folder as {out}.
READERS = (
    ("query", ["query", "{a}"]),
    ("query --describe", ["query", "{a}", "--describe"]),
    ("boundary --archive", ["boundary", "--archive", "{a}"]),
    ("boundary --archive --no-write", ["boundary", "--archive", "{a}", "--no-write"]),
    ("sensitivity", ["sensitivity", "{a}", "--output", "stability_margin_per_s", "--no-write"]),
    ("dispersion", ["dispersion", "{a}", "--columns", "stability_margin_per_s", "--no-write"]),
    ("report", ["report", "{a}", "-o", "{out}/report"]),
    ("merge", ["merge", "{a}", "-o", "{out}/all.h5"]),
    ("merge --copy", ["merge", "{a}", "-o", "{out}/all.h5", "--copy"]),
)


def study(speed_mps):
    """8 modes runs over height (2 shards of 4): another speed is another study."""
    return (f'format_version = 1\nname = "identity"\naircraft = "{ANCE}"\n[analyses.modes]\n'
            f"[parameters]\nspeed_mps = {speed_mps}\n[design]\nkind = \"grid\"\n[[design.parameter]]\n"
            'name = "height_m"\nlinspace = [1.0, 5.0, 8]\n')


def run(gesweep, *args):
    done = subprocess.run([gesweep, *map(str, args)], capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        raise RuntimeError(f"gesweep {' '.join(map(str, args))}: exit {done.returncode}: {done.stderr.strip()}")
    return done


def base(gesweep, folder):
    """s0.h5, s1.h5 (shards 0/2 and 1/2), merged.h5 (virtual over them), and the files the cases put in
    their place: rerun0.h5 (shard 0/2 run again), wrong0.h5 (run for shard 1/2 where shard 0/2 belongs),
    foreign1.h5 (shard 1/2 of another study)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "a.toml").write_text(study(32.0))
    (folder / "b.toml").write_text(study(33.0))
    for index in (0, 1):
        run(gesweep, "run", folder / "a.toml", "-o", folder / f"s{index}.h5", "--shard", f"{index}/2", "-q")
    run(gesweep, "merge", folder / "s0.h5", folder / "s1.h5", "-o", folder / "merged.h5", "-q")
    run(gesweep, "run", folder / "a.toml", "-o", folder / "rerun0.h5", "--shard", "0/2", "-q")
    run(gesweep, "run", folder / "a.toml", "-o", folder / "wrong0.h5", "--shard", "1/2", "-q")
    run(gesweep, "run", folder / "b.toml", "-o", folder / "foreign1.h5", "--shard", "1/2", "-q")
    return folder


def make(gesweep, folder):
    folder = pathlib.Path(folder)
    made = base(gesweep, folder / "base")
    cases = []

    def case(name, change, fragment):
        """A copy of the merged archive and its shards (copies are the same files: same bytes, same
        identities), changed by change(directory); fragment with {d} for the directory."""
        directory = folder / name.replace(" ", "_")
        directory.mkdir()
        for file in ("s0.h5", "s1.h5", "merged.h5"):
            shutil.copyfile(made / file, directory / file)
        change(directory)
        protect = sorted(str(p) for p in directory.iterdir())
        cases.append(Case(name, str(directory / "merged.h5"), fragment.replace("{d}", str(directory)), protect))

    def put(source):
        return lambda d, target: shutil.copyfile(made / source, d / target)

    shard0_range = "holds runs 4..7 of 8 (shard 1/2), expected runs 0..3 of 8 (shard 0/2)"
    case("shard re-run for the wrong shard over another's file", lambda d: put("wrong0.h5")(d, "s0.h5"),
         "virtual_sources = s0.h5: shard file {d}/s0.h5 " + shard0_range)

    def swap(d):
        os.rename(d / "s0.h5", d / "tmp.h5")
        os.rename(d / "s1.h5", d / "s0.h5")
        os.rename(d / "tmp.h5", d / "s1.h5")
    case("two shards swapped", swap, "virtual_sources = s0.h5: shard file {d}/s0.h5 " + shard0_range)
    case("one shard copied over another", lambda d: shutil.copyfile(d / "s1.h5", d / "s0.h5"),
         "virtual_sources = s0.h5: shard file {d}/s0.h5 " + shard0_range)
    case("a shard deleted", lambda d: os.remove(d / "s1.h5"),
         "virtual_sources = s1.h5: shard file {d}/s1.h5 is missing")

    def move(d):
        (d / "elsewhere").mkdir()
        os.rename(d / "s1.h5", d / "elsewhere" / "s1.h5")
    case("a shard moved away", move, "virtual_sources = s1.h5: shard file {d}/s1.h5 is missing")

    def link(d):
        os.remove(d / "s0.h5")
        os.symlink("merged.h5", d / "s0.h5")
    case("a symlink to the merge where a shard was", link,
         "virtual_sources = s0.h5: shard file {d}/s0.h5 is this virtual archive itself")
    case("a shard of another study", lambda d: put("foreign1.h5")(d, "s1.h5"),
         "virtual_sources = s1.h5: shard file {d}/s1.h5 is an archive of another study")
    case("a shard run again (same runs, another archive)", lambda d: put("rerun0.h5")(d, "s0.h5"),
         "virtual_sources = s0.h5: shard file {d}/s0.h5 is not the file that was merged: its archive_id is ")

    # Archives written before identities (old_archives/README.md): still checked by their mapping.
    def old(name, change, fragment, archive="merged.h5"):
        directory = folder / name.replace(" ", "_")
        shutil.copytree(OLD_ARCHIVES, directory)
        change(directory)
        protect = sorted(str(p) for p in directory.iterdir() if p.suffix == ".h5")
        cases.append(Case(name, str(directory / archive), fragment.replace("{d}", str(directory)), protect))

    old("old archives: two shards swapped", swap, "virtual_sources = s0.h5: shard file {d}/s0.h5 holds runs "
        "4..7 of 8 (shard 1/2), expected runs 0..3 of 8")
    old("old archives: a shard deleted", lambda d: os.remove(d / "s1.h5"),
        "virtual_sources = s1.h5: shard file {d}/s1.h5 is missing")

    def cycle(d):
        # nested.h5 reads merged.h5; nested2.h5 reads nested.h5: in merged.h5's place, a cycle.
        os.rename(d / "merged.h5", d / "merged_away.h5")
        os.rename(d / "nested2.h5", d / "merged.h5")
    old("a cycle of two virtual archives", cycle,
        "virtual_sources = nested.h5: shard file {d}/nested.h5 is the virtual archive {d}/nested.h5 again: "
        "virtual archives that read each other in a cycle cannot be read", archive="nested.h5")
    return cases
