#!/usr/bin/python3
"""Runs the hostile-input corpus against the real gesweep binary.

tests/bad_inputs/aircraft/NAME.toml   aircraft files, loaded by `gesweep modes --aircraft NAME.toml`
tests/bad_inputs/study/NAME.toml      study files, run by `gesweep run NAME.toml -o <tmp>/out.h5`
NAME.expect                           a fragment the one-line error message must contain

Every case must exit 2, print exactly one line on stderr containing the fragment, and leave no file
in the output directory (but the ones a case put there on purpose, unchanged). Cases that need setup
(unreadable paths, symlink loops, FIFOs, archives, shards of different studies, ...) are in the
special_*_cases functions below."""
import os
import pathlib
import resource
import shutil
import subprocess
import sys
import tempfile

GESWEEP = os.path.abspath(sys.argv[1])
ROOT = pathlib.Path(__file__).resolve().parent
# An AddressSanitizer build (./scripts/test --sanitize) cannot run under an address-space limit.
# GCC links the runtime dynamically (libasan.so): the binary names its entry point, not the runtime's text.
SANITIZED = b"__asan_init" in pathlib.Path(GESWEEP).read_bytes()
failures = []
count = 0


def check(name, args, fragment, out_dir, keep=(), timeout=120, memory_bytes=None):
    """Runs one case. `keep`: files the case put in out_dir on purpose (they must be left unchanged);
    `timeout`: seconds before a hang counts as a failure; `memory_bytes`: an address-space limit, so a
    case that would eat the machine's memory fails fast instead (not under AddressSanitizer, whose
    shadow memory needs terabytes of address space)."""
    global count
    count += 1
    before = {n: (pathlib.Path(out_dir) / n).read_bytes() for n in keep if (pathlib.Path(out_dir) / n).is_file()}
    limit = None
    if memory_bytes is not None and not SANITIZED:
        limit = lambda: resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))  # noqa: E731
    try:
        result = subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=timeout, preexec_fn=limit)
    except subprocess.TimeoutExpired:
        failures.append(f"{name}: still running after {timeout} s (killed): a hostile input must be refused at once")
        return
    lines = result.stderr.strip().splitlines()
    problems = []
    if result.returncode != 2:
        problems.append(f"exit {result.returncode}, expected 2")
    if len(lines) != 1:
        problems.append(f"{len(lines)} stderr lines, expected 1")
    if not any(fragment in line for line in lines):
        problems.append(f"no line contains {fragment!r}")
    left = sorted(p.name for p in pathlib.Path(out_dir).iterdir() if p.name not in keep)
    if left:
        problems.append(f"left files behind: {left}")
    changed = [n for n, data in before.items()
               if not (pathlib.Path(out_dir) / n).is_file() or (pathlib.Path(out_dir) / n).read_bytes() != data]
    if changed:
        problems.append(f"changed files it must not touch: {changed}")
    if problems:
        failures.append(f"{name}: {'; '.join(problems)}\n    stderr: {result.stderr.strip()[:400]}")


def corpus(kind, make_args):
    folder = ROOT / kind
    if not folder.is_dir():
        return
    for case in sorted(folder.glob("*.toml")):
        fragment = case.with_suffix(".expect").read_text().strip()
        with tempfile.TemporaryDirectory() as out_dir:
            check(f"{kind}/{case.name}", make_args(str(case), out_dir), fragment, out_dir)


corpus("aircraft", lambda path, out: ["modes", "--aircraft", path, "--speed-mps", "30", "--table-heights"])
corpus("study", lambda path, out: ["run", path, "-o", os.path.join(out, "out.h5")])


def special_aircraft_cases():
    ance = pathlib.Path("studies/aircraft/ance.toml").resolve()
    with tempfile.TemporaryDirectory() as tmp, tempfile.TemporaryDirectory() as out:
        tmp = pathlib.Path(tmp)
        loop_a, loop_b = tmp / "loop_a.toml", tmp / "loop_b.toml"
        loop_a.symlink_to(loop_b)
        loop_b.symlink_to(loop_a)
        check("aircraft symlink loop", ["modes", "--aircraft", str(loop_a), "--speed-mps", "30", "--table-heights"],
              "symbolic links", out)
        check("aircraft is a directory", ["modes", "--aircraft", str(tmp), "--speed-mps", "30", "--table-heights"],
              "found a directory", out)
        # A value cut at the end of a line (found by fuzz_study in study files; the aircraft loader
        # shares the TOML reader): toml++ quotes the line break it saw; the message must stay one line.
        truncated = tmp / "truncated_value.toml"
        truncated.write_text(ance.read_text().replace("cg_over_chord = 0.25", "cg_over_chord = t", 1))
        check("aircraft value cut at a line end", ["modes", "--aircraft", str(truncated), "--speed-mps", "30",
                                                   "--table-heights"], "TOML syntax error", out)
        if os.geteuid() != 0:  # root reads any file, so an unreadable file cannot be made as root
            locked = tmp / "locked.toml"
            locked.write_text(ance.read_text())
            locked.chmod(0)
            check("aircraft unreadable", ["modes", "--aircraft", str(locked), "--speed-mps", "30", "--table-heights"],
                  "cannot open", out)


special_aircraft_cases()


def study_text(aircraft, extra=""):
    """A valid one-run study of `aircraft` (an absolute path or one relative to the study)."""
    return (f'format_version = 1\nname = "hostile"\naircraft = "{aircraft}"\n[analyses.modes]\n'
            f"[parameters]\nspeed_mps = 32.0208\n{extra}")


def grid_study(aircraft, speed_mps):
    """A valid 8-run study (for shards): its speed makes it another study when it differs."""
    return (f'format_version = 1\nname = "shards"\naircraft = "{aircraft}"\n[analyses.modes]\n'
            f"[parameters]\nspeed_mps = {speed_mps}\n[design]\nkind = \"grid\"\n[[design.parameter]]\n"
            f'name = "height_m"\nlinspace = [1.0, 5.0, 8]\n')


def special_study_cases():
    """Study, archive and merge cases that need setup: paths that cannot be read, symlink loops, a
    FIFO, an endless device, a study that names itself through a symlink, archives in the way, shards
    of different studies."""
    ance = pathlib.Path("studies/aircraft/ance.toml").resolve()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        good = tmp / "good.toml"
        good.write_text(study_text(ance, "height_m = 2.0\n"))

        def run(name, args, fragment, keep=(), **kwargs):
            with tempfile.TemporaryDirectory() as out:
                for n, text in keep:
                    (pathlib.Path(out) / n).write_bytes(text)
                args = [a.replace("{out}", out) for a in args]
                check(name, args, fragment, out, keep=[n for n, _ in keep], **kwargs)

        # Study paths that cannot be read.
        loop_a, loop_b = tmp / "loop_a.toml", tmp / "loop_b.toml"
        loop_a.symlink_to(loop_b)
        loop_b.symlink_to(loop_a)
        run("study symlink loop", ["run", str(loop_a), "-o", "{out}/out.h5"], "symbolic links")
        run("study is a directory", ["run", str(tmp), "-o", "{out}/out.h5"], "found a directory")
        run("study missing", ["run", str(tmp / "no_such_study.toml"), "-o", "{out}/out.h5"], "no such file")
        if os.geteuid() != 0:  # root reads any file
            locked = tmp / "locked.toml"
            locked.write_text(good.read_text())
            locked.chmod(0)
            run("study unreadable", ["run", str(locked), "-o", "{out}/out.h5"], "cannot open")
        fifo = tmp / "fifo.toml"
        os.mkfifo(fifo)
        run("study is a FIFO (nobody writes it)", ["run", str(fifo), "-o", "{out}/out.h5"], "not a regular file",
            timeout=10)
        run("study is an endless device", ["run", "/dev/zero", "-o", "{out}/out.h5"], "not a regular file",
            timeout=10, memory_bytes=2 << 30)

        # Files a study names that cannot be read.
        aircraft_loop = tmp / "aircraft_loop.toml"
        aircraft_loop.write_text(study_text("loop_a.toml", "height_m = 2.0\n"))
        run("aircraft symlink loop named by a study", ["run", str(aircraft_loop), "-o", "{out}/out.h5"],
            "symbolic links")
        alias = tmp / "alias.toml"
        self_study = tmp / "self_by_symlink.toml"
        alias.symlink_to(self_study)
        self_study.write_text(study_text("alias.toml", "height_m = 2.0\n"))
        run("study names itself as aircraft through a symlink", ["run", str(self_study), "-o", "{out}/out.h5"],
            "not this study file itself")
        csv_loop_a, csv_loop_b = tmp / "loop_a.csv", tmp / "loop_b.csv"
        csv_loop_a.symlink_to(csv_loop_b)
        csv_loop_b.symlink_to(csv_loop_a)
        csv_study = tmp / "csv_loop.toml"
        csv_study.write_text(study_text(ance, '[design]\nkind = "list"\ncsv = "loop_a.csv"\n'))
        run("design CSV symlink loop", ["run", str(csv_study), "-o", "{out}/out.h5"], "symbolic links")

        # A grid with one axis of 10^8 values and time series: refused for its storage estimate. The
        # refusal must not need memory per value beyond the values themselves (8 bytes each).
        huge = tmp / "huge_axis.toml"
        huge.write_text(study_text(ance, "pulse_duration_s = 0.2\n").replace(
            "[analyses.modes]", "[analyses.open_loop]\n[output]\ntime_series = true").replace(
            "speed_mps = 32.0208\n", "") + '[design]\nkind = "grid"\n[[design.parameter]]\nname = "height_m"\n'
            "linspace = [1.0, 13.0, 100000000]\n[[design.parameter]]\nname = \"speed_mps\"\n"
            "values = [30.0, 40.0]\n")
        if not SANITIZED:
            run("grid axis of 10^8 values with time series", ["run", str(huge), "-o", "{out}/out.h5"],
                "refusing it: the archive would need about", timeout=60, memory_bytes=2 << 30)

        # Archive paths.
        run("archive in a missing directory", ["run", str(good), "-o", "{out}/no/such/dir/out.h5"], "does not exist")
        with tempfile.TemporaryDirectory() as out:
            (pathlib.Path(out) / "out.h5").mkdir()
            check("archive path is a directory", ["run", str(good), "-o", f"{out}/out.h5"], "is a directory", out,
                  keep=["out.h5"])
        run("archive exists (no --resume, no --force)", ["run", str(good), "-o", "{out}/out.h5"], "already exists",
            keep=[("out.h5", b"not an archive, but someone's file")])
        run("resume of a file that is not an archive", ["run", str(good), "-o", "{out}/out.h5", "--resume"],
            "not an HDF5 file", keep=[("out.h5", b"not an archive, but someone's file")])
        run("--resume with --force", ["run", str(good), "-o", "{out}/out.h5", "--resume", "--force"],
            "cannot be combined")
        run("bad --shard", ["run", str(good), "-o", "{out}/out.h5", "--shard", "3/3"], "expected i/N")
        run("bad --threads", ["run", str(good), "-o", "{out}/out.h5", "--threads", "-2"], "expected 1 to 4096")

        # Shards and merges.
        shards = tmp / "shards"
        shards.mkdir()
        study_a, study_b = shards / "a.toml", shards / "b.toml"
        study_a.write_text(grid_study(ance, 32.0))
        study_b.write_text(grid_study(ance, 33.0))
        made = {}
        for study, shard in ((study_a, 0), (study_a, 1), (study_b, 1)):
            archive = shards / f"{study.stem}{shard}.h5"
            result = subprocess.run([GESWEEP, "run", str(study), "-o", str(archive), "--shard", f"{shard}/2", "-q"],
                                    capture_output=True, text=True, timeout=120)
            made[archive.name] = result.returncode == 0
        if all(made.values()):
            a0, a1, b1 = (str(shards / n) for n in ("a0.h5", "a1.h5", "b1.h5"))
            run("merge of shards from different studies", ["merge", a0, b1, "-o", "{out}/all.h5"],
                "shards must come from the same study")
            run("merge with a shard missing", ["merge", a0, "-o", "{out}/all.h5"], "not given")
            run("merge of overlapping shards", ["merge", a0, a0, a1, "-o", "{out}/all.h5"], "overlaps")
            run("merge of a study file", ["merge", a0, str(study_a), "-o", "{out}/all.h5"], "not an HDF5 file")
            run("merge of a symlink loop", ["merge", a0, str(loop_a), "-o", "{out}/all.h5"], "symbolic links")
            run("merge into a missing directory", ["merge", a0, a1, "-o", "{out}/no/such/all.h5"], "does not exist")
            with tempfile.TemporaryDirectory() as out:
                (pathlib.Path(out) / "all.h5").mkdir()
                check("merge --force onto a directory", ["merge", a0, a1, "-o", f"{out}/all.h5", "--force"],
                      "is a directory", out, keep=["all.h5"])
            # Resuming an archive with another study refuses and leaves the archive as it was.
            with tempfile.TemporaryDirectory() as out:
                shutil.copyfile(a0, pathlib.Path(out) / "a0.h5")
                check("resume with another study", ["run", str(study_b), "-o", f"{out}/a0.h5", "--shard", "0/2",
                                                    "--resume"], "cannot resume", out, keep=["a0.h5"])
        else:
            failures.append(f"shards for the merge cases could not be made: {made}")


special_study_cases()

for failure in failures:
    print("FAIL", failure)
print(f"{count} hostile inputs, {count - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures or count == 0 else 0)
