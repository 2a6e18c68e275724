"""Damaged archives (issue 26, item 8; docs/reliability.md 11.4), used by run_bad_inputs.py
(`damaged_archive_cases`) and by tests/python/test_damaged_archives.py.

1. The eight files of tests/fuzz/hdf5_defects on which libhdf5 1.10.8 itself loops for ever, reads out
   of bounds or frees a bad pointer (README.md there): every entry point that opens an archive a person
   names must answer with one line naming the file, exit 2, within 5 s, the file's bytes unchanged.
2. `run --resume` onto a file that is not a resumable archive of its study (a truncated archive of
   another study, an archive cut to its first 2 KiB, a zero-length file, a text file, an archive of
   another study with bytes flipped in its metadata) refuses with one line, exit 2, and leaves the
   file byte for byte as it was (before this change a truncated archive was extended in place first).

The fragments are the words of the guard (engine/archive/archive_probe.cc) and of the reader, spelled
out here, not taken from a run of the code under test."""
import hashlib
import pathlib
import subprocess

ROOT = pathlib.Path(__file__).resolve().parent
ANCE = (ROOT.parent.parent / "studies" / "aircraft" / "ance.toml").resolve()
DEFECTS = ROOT.parent / "fuzz" / "hdf5_defects"

# The eight inputs: fuzz_archive's form (first byte 0), the file is the rest.
DEFECT_NAMES = (
    "dense_link_bad_free_a",
    "dense_link_bad_free_b",
    "global_heap_free_space_size_zero_a",
    "global_heap_free_space_size_zero_b",
    "global_heap_free_space_size_zero_c",
    "global_heap_object_past_collection_a",
    "global_heap_object_past_collection_b",
    "object_header_message_past_block",
)

# The one line every entry point gives for them names the file first. When libhdf5 crashes or hangs
# in the check's child process, the rest is what it did ("crashed (SIGSEGV)", "did not finish
# decoding the file within 3 s", "failed" under AddressSanitizer) and then DAMAGED. On the bad free
# and the overflowing read (dense_link_*, object_header_*) libhdf5's outcome depends on the heap's
# layout: in a Release build it may also fail cleanly there, and then the line is the reader's own
# refusal ("cannot list its datasets", "not a gesweep archive"), sent back from the child: the file
# is never decoded again in the process itself (on main the Python process died of SIGABRT on both
# dense_link files). The five below break libhdf5 the same way every time.
DAMAGED = ": a damaged archive (docs/reliability.md, 11.4"
ALWAYS_BREAKS = (
    "global_heap_free_space_size_zero_a",  # loops for ever
    "global_heap_free_space_size_zero_b",
    "global_heap_free_space_size_zero_c",
    "global_heap_object_past_collection_a",  # memcpy of 6.99e18 bytes
    "global_heap_object_past_collection_b",  # memcpy of 7.2e16 bytes
)

# The other commands that open an archive a person names, each given it as {a} (and a scratch
# folder as {out}); run_bad_inputs.py puts ONE_OF_EACH through them.
OTHER_READERS = (
    ("boundary --archive --no-write", ["boundary", "--archive", "{a}", "--no-write"]),
    ("sensitivity", ["sensitivity", "{a}", "--output", "stability_margin_per_s", "--no-write"]),
    ("dispersion", ["dispersion", "{a}", "--columns", "stability_margin_per_s", "--no-write"]),
    ("report", ["report", "{a}", "-o", "{out}/report"]),
)
ONE_OF_EACH = ("global_heap_free_space_size_zero_a", "global_heap_object_past_collection_a",
               "dense_link_bad_free_a")

# Seconds within which each must be refused (the brief: 5 s; under AddressSanitizer startup alone
# takes a second or two, so there the bound is looser).
SECONDS = 5.0
SECONDS_SANITIZED = 20.0


def sha256(path):
    return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()


def defect_files(folder):
    """The eight damaged archives written as plain files into `folder`: {name: path}."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    made = {}
    for name in DEFECT_NAMES:
        data = (DEFECTS / name).read_bytes()
        assert data[0] == 0, f"{name}: not a raw-file input (first byte {data[0]})"
        path = folder / f"{name}.h5"
        path.write_bytes(data[1:])
        made[name] = path
    return made


def study_text(speed_mps, name="damaged"):
    """16 modes runs over height, in batches of 4: another speed is another study."""
    return (f'format_version = 1\nname = "{name}"\naircraft = "{ANCE}"\n[analyses.modes]\n[output]\n'
            f"chunk_runs = 4\n[parameters]\nspeed_mps = {speed_mps}\n[design]\nkind = \"grid\"\n"
            '[[design.parameter]]\nname = "height_m"\nlinspace = [1.0, 5.0, 16]\n')


def run(gesweep, *args):
    done = subprocess.run([gesweep, *map(str, args)], capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        raise RuntimeError(f"gesweep {' '.join(map(str, args))}: exit {done.returncode}: {done.stderr.strip()}")
    return done


def resume_targets(gesweep, folder):
    """The study a resume is asked for (folder/study.toml) and the files it is pointed at, none of them
    a resumable archive of it: [(name, path, fragment)]. The fragments: the reader's words for each
    (the whole line's start: the file it names, then why)."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    study = folder / "study.toml"
    study.write_text(study_text(32.0))
    other = folder / "other.toml"
    other.write_text(study_text(33.0))
    complete_other = folder / "complete_other.h5"
    run(gesweep, "run", other, "-o", complete_other, "-q")
    data = complete_other.read_bytes()
    complete_other.unlink()
    targets = []

    def target(name, content, fragment):
        path = folder / name
        path.write_bytes(content)
        targets.append((name, path, fragment.replace("{path}", str(path))))

    # Shorter than HDF5 recorded (a write cut half-way leaves that): the case that was extended in
    # place before this change. Its last 1000 bytes gone, a copy extended with zeros opens, and is
    # another study's; cut to 3/4 or to 2 KiB, not even the copy is an archive.
    fingerprint = "command line: -o = {path}: cannot resume: the archive has study fingerprint"
    no_format = '{path}: format: not a gesweep archive (no format = "gesweep-archive") (in a copy extended'
    target("truncated_other_study.h5", data[:-1000], fingerprint)
    target("three_quarters.h5", data[: len(data) * 3 // 4], no_format)
    target("first_2k.h5", data[:2048], no_format)
    target("empty.h5", b"", "{path}: not an HDF5 file")
    target("text.h5", b"height_m,speed_mps\n1.0,32.0\n", "{path}: not an HDF5 file")
    flipped = bytearray(data)
    for offset in range(48, 48 + 64):  # the superblock's end and what follows: checksummed metadata
        flipped[offset] ^= 0xFF
    target("flipped_other_study.h5", bytes(flipped), '{path}: format: not a gesweep archive')
    return study, targets
