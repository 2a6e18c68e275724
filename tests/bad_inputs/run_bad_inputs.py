#!/usr/bin/python3
"""Runs the hostile-input corpus against the real gesweep binary.

tests/bad_inputs/aircraft/NAME.toml   aircraft files, loaded by `gesweep modes --aircraft NAME.toml`
tests/bad_inputs/study/NAME.toml      study files, run by `gesweep run NAME.toml -o <tmp>/out.h5`
NAME.expect                           a fragment the one-line error message must contain

Every case must exit with its code (2, bad input, unless the case says otherwise), print exactly one
line on stderr containing the fragment (and none of its forbidden fragments), that line printable:
valid UTF-8 without control characters (a person's text in it escaped), and leave nothing behind:
no file in the output directory but the ones a case put there on purpose; a protected copy of every
input -- every file named on its command line, the files the case names as protected, the shipped
aircraft -- byte-identical afterwards (compared as cmp does); nothing new beside any of them. Cases
that need setup (unreadable paths, symlink loops, FIFOs, archives, shards of different studies, an
output that is an input, ...) are in the special_*_cases functions below."""
import filecmp
import os
import pathlib
import resource
import shutil
import stat
import subprocess
import sys
import tempfile

GESWEEP = os.path.abspath(sys.argv[1])
ROOT = pathlib.Path(__file__).resolve().parent
ANCE = (ROOT.parent.parent / "studies" / "aircraft" / "ance.toml").resolve()
# An AddressSanitizer build (./scripts/test --sanitize) cannot run under an address-space limit.
# GCC links the runtime dynamically (libasan.so): the binary names its entry point, not the runtime's text.
SANITIZED = b"__asan_init" in pathlib.Path(GESWEEP).read_bytes()
failures = []
count = 0


def snapshot(paths, copies):
    """Protected copies: for each path, what it is (lstat mode, symlink target, device) and, for a
    regular file, a copy of its bytes in `copies`."""
    taken = {}
    for index, path in enumerate(paths):
        path = pathlib.Path(path)
        if not os.path.lexists(path):
            continue
        info = os.lstat(path)
        entry = {"mode": stat.S_IFMT(info.st_mode), "rdev": info.st_rdev, "copy": None, "link": None}
        if stat.S_ISLNK(info.st_mode):
            entry["link"] = os.readlink(path)
        elif stat.S_ISREG(info.st_mode):
            entry["copy"] = pathlib.Path(copies) / f"{index}"
            shutil.copyfile(path, entry["copy"])
        taken[str(path)] = entry
    return taken


def changed_inputs(taken):
    """Names of protected paths that are not as they were (missing, another kind of file, another
    symlink target, other bytes)."""
    changed = []
    for path, entry in taken.items():
        if not os.path.lexists(path):
            changed.append(f"{path} (gone)")
            continue
        info = os.lstat(path)
        if stat.S_IFMT(info.st_mode) != entry["mode"] or info.st_rdev != entry["rdev"]:
            changed.append(f"{path} (now another kind of file)")
        elif entry["link"] is not None and os.readlink(path) != entry["link"]:
            changed.append(f"{path} (the symlink points elsewhere)")
        elif entry["copy"] is not None and not filecmp.cmp(path, entry["copy"], shallow=False):
            changed.append(f"{path} (other bytes)")
    return changed


def printable_problem(raw):
    """Why the stderr bytes are not printable one-line text, or None."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        return f"stderr is not valid UTF-8 ({error})"
    bad = [c for c in text.rstrip("\n") if (ord(c) < 0x20 and c != "\n") or 0x7F <= ord(c) <= 0x9F]
    return f"stderr holds control characters {bad!r}" if bad else None


def watched_directories(paths, out_dir):
    """Directories whose listing must not grow: the output directory and the folders of the protected
    inputs (not system folders)."""
    folders = {str(pathlib.Path(out_dir))}
    for path in paths:
        parent = str(pathlib.Path(os.path.abspath(path)).parent)
        if not parent.startswith(("/dev", "/proc", "/sys")):
            folders.add(parent)
    return {folder: set(os.listdir(folder)) for folder in folders if os.path.isdir(folder)}


def check(name, args, fragment, out_dir, keep=(), timeout=120, memory_bytes=None, exit_code=2, protect=(),
          forbid=(), after=None):
    """Runs one case. `keep`: files the case put in out_dir on purpose (they must be left unchanged);
    `timeout`: seconds before a hang counts as a failure; `memory_bytes`: an address-space limit, so a
    case that would eat the machine's memory fails fast instead (not under AddressSanitizer, whose
    shadow memory needs terabytes of address space); `exit_code`: the code expected; `protect`: more
    inputs that must be byte-identical afterwards; `forbid`: fragments the line must not contain;
    `after`: a function returning a list of further problems."""
    global count
    count += 1
    out_dir = pathlib.Path(out_dir)
    inputs = [a for a in args if os.path.lexists(a) and not os.path.isdir(a)]
    inputs += [str(out_dir / n) for n in keep] + [str(p) for p in protect] + [str(ANCE)]
    with tempfile.TemporaryDirectory() as copies:
        taken = snapshot(inputs, copies)
        listings = watched_directories(list(taken) + [str(p) for p in protect if os.path.isdir(p)], out_dir)
        limit = None
        if memory_bytes is not None and not SANITIZED:
            limit = lambda: resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))  # noqa: E731
        try:
            result = subprocess.run([GESWEEP, *args], capture_output=True, timeout=timeout, preexec_fn=limit)
        except subprocess.TimeoutExpired:
            failures.append(f"{name}: still running after {timeout} s (killed): a hostile input must be refused at once")
            return
        stderr = result.stderr.decode("utf-8", "replace")
        lines = stderr.strip().splitlines()
        problems = []
        if result.returncode != exit_code:
            problems.append(f"exit {result.returncode}, expected {exit_code}")
        if len(lines) != 1:
            problems.append(f"{len(lines)} stderr lines, expected 1")
        if not any(fragment in line for line in lines):
            problems.append(f"no line contains {fragment!r}")
        problems += [f"the line contains {f!r}" for f in forbid if any(f in line for line in lines)]
        unprintable = printable_problem(result.stderr)
        if unprintable:
            problems.append(unprintable)
        for folder, before in listings.items():
            new = sorted(set(os.listdir(folder)) - before - set(keep)) if os.path.isdir(folder) else []
            if new:
                problems.append(f"left files behind in {folder}: {new}")
        changed = changed_inputs(taken)
        if changed:
            problems.append(f"changed inputs it must not touch: {changed}")
        if after is not None:
            problems += after()
        if problems:
            failures.append(f"{name}: {'; '.join(problems)}\n    stderr: {stderr.strip()[:400]}")


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
        run("bad --threads", ["run", str(good), "-o", "{out}/out.h5", "--threads", "-2"], "--threads = -2: expected a whole number in [1, 4096]")

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


def make_archive(study, archive, shard="0/1"):
    result = subprocess.run([GESWEEP, "run", str(study), "-o", str(archive), "--shard", shard, "-q"],
                            capture_output=True, text=True, timeout=120)
    if result.returncode != 0:
        failures.append(f"could not make {archive}: {result.stderr.strip()[:300]}")
    return result.returncode == 0


def damaged_archives(good, folder):
    """Archives broken the ways of issue 13 (h5py, as another program would): a results dataset
    shorter than runs/status, a gesweep format attribute without the root attributes, the file cut
    short, random bytes behind the HDF5 signature, a file of arbitrary groups."""
    import h5py  # Debian's python3-h5py
    import numpy as np
    made = {}
    short = folder / "short_result.h5"
    shutil.copyfile(good, short)
    with h5py.File(short, "r+") as f:
        path = "results/modes/stability_margin_per_s"
        values = f[path][...]
        attrs = dict(f[path].attrs)
        del f[path]
        f[path] = values[:-1]
        for key, value in attrs.items():
            f[path].attrs[key] = value
    made["short"] = short
    no_attrs = folder / "no_root_attributes.h5"
    shutil.copyfile(good, no_attrs)
    with h5py.File(no_attrs, "r+") as f:
        for key in ("run_count", "design_runs", "first_run", "chunk_runs"):
            del f.attrs[key]
    made["no_attrs"] = no_attrs
    data = pathlib.Path(good).read_bytes()
    cut = folder / "cut.h5"
    cut.write_bytes(data[:len(data) // 2])
    made["cut"] = cut
    noise = folder / "noise.h5"
    noise.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes((i * 97 + 13) % 256 for i in range(4000)))
    made["noise"] = noise
    foreign = folder / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f.create_group("a/b")
        f["a/values"] = np.arange(10.0)
        f.attrs["title"] = "written by another program"
    made["foreign"] = foreign
    return made


def hardening_cases():
    """Issue 13: an output never replaces an input; all work is bounded; one table of limits for
    flags and study files; archives that cannot crash a reader; one printable line for every failure."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        aircraft = tmp / "aircraft.toml"
        shutil.copyfile(ANCE, aircraft)
        study = tmp / "study.toml"
        study.write_text(study_text("aircraft.toml", "height_m = 2.0\n"))
        csv = tmp / "rows.csv"
        csv.write_text("height_m\n2.0\n3.0\n")
        list_study = tmp / "list.toml"
        list_study.write_text(study_text("aircraft.toml", '[design]\nkind = "list"\ncsv = "rows.csv"\n'))
        grid = tmp / "grid.toml"
        grid.write_text(grid_study("aircraft.toml", 32.0))
        (tmp / "hard.h5").unlink(missing_ok=True)
        os.link(study, tmp / "hard.h5")
        (tmp / "soft.h5").symlink_to(aircraft)
        fifo = tmp / "fifo.h5"
        os.mkfifo(fifo)
        # A character device of our own (a copy of /dev/null's node): a gesweep that wrongly writes to
        # it replaces this node, never the system's /dev/null. Making one needs root.
        device = tmp / "null_device"
        try:
            os.mknod(device, stat.S_IFCHR | 0o666, os.makedev(1, 3))
        except PermissionError:
            device = None
            print("SKIP the cases that write onto a character device: making one needs root")
        partial_study = tmp / "out.h5.partial"
        partial_study.write_text(study.read_text())

        def run(name, args, fragment, **kwargs):
            with tempfile.TemporaryDirectory() as out:
                check(name, [a.replace("{out}", out) for a in args], fragment, out, **kwargs)

        # 1. An output never replaces an input (one check: engine/common/output_guard.h).
        run("run -o the study --force", ["run", str(study), "-o", str(study), "--force"], "is the study file")
        run("run -o the study (no --force)", ["run", str(study), "-o", str(study)], "is the study file")
        run("run -o the study --resume", ["run", str(study), "-o", str(study), "--resume"], "is the study file")
        run("run --dry-run -o the study", ["run", str(study), "-o", str(study), "--dry-run"], "is the study file")
        run("run -o the aircraft file --force", ["run", str(study), "-o", str(aircraft), "--force"],
            "is the aircraft file")
        run("run -o the design CSV --force", ["run", str(list_study), "-o", str(csv), "--force"],
            "is the design CSV file")
        run("run -o a hard link to the study --force", ["run", str(study), "-o", str(tmp / "hard.h5"), "--force"],
            "a hard link or a symlink to it")
        run("run -o a symlink to the aircraft --force", ["run", str(study), "-o", str(tmp / "soft.h5"), "--force"],
            "is the aircraft file")
        run("run -o X whose X.partial is the study --force",
            ["run", str(partial_study), "-o", str(tmp / "out.h5"), "--force"], "writing it would replace")
        if device:
            run("run --force onto a character device", ["run", str(study), "-o", str(device), "--force"],
                "is a character device, not a regular file")
        run("run --force onto a FIFO", ["run", str(study), "-o", str(fifo), "--force"], "is a FIFO, not a regular file",
            timeout=20)

        # 2. Bounded work: flags (the study files are in study/).
        run("simulate --dt-s 1e-300", ["simulate", "--aircraft", str(ANCE), "--height-m", "2", "--speed-mps", "32",
                                       "--dt-s", "1e-300"], "--dt-s = 1e-300: expected a number in [1e-06, 10] s")
        run("simulate --duration-s 1e308", ["simulate", "--aircraft", str(ANCE), "--height-m", "2", "--speed-mps",
                                            "32", "--duration-s", "1e308"],
            "--duration-s = 1e308: expected a number in (0, 100000] s")
        run("simulate: 1e9 RK4 steps", ["simulate", "--aircraft", str(ANCE), "--height-m", "2", "--speed-mps", "32",
                                        "--duration-s", "1e5", "--dt-s", "1e-4", "--summary-only"],
            "--duration-s = 100000 s / --dt-s = 0.0001 s = 1000000000 steps")
        run("simulate: dopri5 with a tiny largest step", ["simulate", "--aircraft", str(ANCE), "--height-m", "2",
                                                          "--speed-mps", "32", "--integrator", "dopri5",
                                                          "--max-step-s", "1e-6", "--duration-s", "1000"],
            "--max-step-s = 1e-06: expected at most 100000000 integration steps per run")
        run("land --max-step-s 1e-6", ["land", "--aircraft", str(ANCE), "--max-step-s", "1e-6"],
            "--max-step-s = 1e-06: expected at most 100000000 integration steps per run, but --time-limit-s (automatic)")
        run("land --time-limit-s 1e308", ["land", "--aircraft", str(ANCE), "--time-limit-s", "1e308"],
            "--time-limit-s = 1e308: expected a number in (0, 100000] s")
        run("run --dry-run of a study of 3e10 steps per run",
            ["run", str(ROOT / "study" / "step_count_rk4.toml"), "--dry-run"], "expected a number in [1e-06, 10] s",
            timeout=20)
        run("run --dry-run-budget-s 0", ["run", str(study), "--dry-run", "--dry-run-budget-s", "0"],
            "--dry-run-budget-s = 0: expected a number in (0, 600] s")

        # 3. One table of limits: every flag says flag, value and range.
        run("modes --speed-mps 1e308", ["modes", "--aircraft", str(ANCE), "--speed-mps", "1e308", "--heights-m", "2"],
            "--speed-mps = 1e308: expected a number in [1, 300] m/s")
        run("modes --speed-mps 1e-300", ["modes", "--aircraft", str(ANCE), "--speed-mps", "1e-300", "--heights-m", "2"],
            "--speed-mps = 1e-300: expected a number in [1, 300] m/s")
        run("modes --speed-mps 1e400 (past a double)", ["modes", "--aircraft", str(ANCE), "--speed-mps", "1e400",
                                                        "--heights-m", "2"],
            "--speed-mps = 1e400: is past the largest magnitude a double can hold", forbid=["expected a number"])
        run("modes --speed-mps nan", ["modes", "--aircraft", str(ANCE), "--speed-mps", "nan", "--heights-m", "2"],
            "--speed-mps = nan: expected a number in [1, 300] m/s")
        run("modes --heights-m 1e308", ["modes", "--aircraft", str(ANCE), "--speed-mps", "32", "--heights-m", "2,1e308"],
            "--heights-m = 1e+308: expected a number in (0, 11000] m")
        run("modes --heights-m 1e-400 (below a double)", ["modes", "--aircraft", str(ANCE), "--speed-mps", "32",
                                                          "--heights-m", "1e-400"],
            "closer to 0 than a double can hold")
        run("simulate --height-m 1e308", ["simulate", "--aircraft", str(ANCE), "--height-m", "1e308", "--speed-mps",
                                          "32"], "--height-m = 1e308: expected a number in (0, 11000] m")
        run("simulate --elevator-deg 1e308", ["simulate", "--aircraft", str(ANCE), "--height-m", "2", "--speed-mps",
                                              "32", "--elevator-deg", "1e308"],
            "--elevator-deg = 1e308: expected a number in [-30, 30] deg")
        run("boundary --speeds-mps 30,1e308", ["boundary", "--aircraft", str(ANCE), "--speeds-mps", "30,1e308"],
            "--speeds-mps = 1e+308: expected a number in [1, 300] m/s")
        run("land --glide-slope-deg 45", ["land", "--aircraft", str(ANCE), "--glide-slope-deg", "45"],
            "--glide-slope-deg = 45: expected a number in (0, 10] deg")
        # The moving atmosphere (docs/model.md section 9): each flag in its words.
        run("simulate --turbulence foo", ["simulate", "--aircraft", str(ANCE), "--height-m", "2", "--speed-mps",
                                          "32", "--turbulence", "foo"],
            "--turbulence = 'foo': expected none or dryden")
        run("simulate --turbulence-sigma-w-mps -1", ["simulate", "--aircraft", str(ANCE), "--height-m", "2",
                                                     "--speed-mps", "32", "--turbulence", "dryden",
                                                     "--turbulence-sigma-w-mps", "-1"],
            "--turbulence-sigma-w-mps = -1: expected a number in [0, 50] m/s")
        run("simulate --gust-half-length-m 0", ["simulate", "--aircraft", str(ANCE), "--height-m", "2",
                                                "--speed-mps", "32", "--gust-half-length-m", "0"],
            "--gust-half-length-m = 0: expected a number in (0, 10000] m")
        run("simulate --wind-20ft-mps 1e308", ["simulate", "--aircraft", str(ANCE), "--height-m", "2",
                                               "--speed-mps", "32", "--wind-20ft-mps", "1e308"],
            "--wind-20ft-mps = 1e308: expected a number in [-50, 50] m/s")
        run("land --turbulence foo", ["land", "--aircraft", str(ANCE), "--turbulence", "foo"],
            "--turbulence = 'foo': expected none or dryden")
        run("land --turbulence-sigma-w-mps -0.5", ["land", "--aircraft", str(ANCE), "--turbulence", "dryden",
                                                   "--turbulence-sigma-w-mps", "-0.5"],
            "--turbulence-sigma-w-mps = -0.5: expected a number in [0, 50] m/s")
        run("land --gust-half-length-m 0", ["land", "--aircraft", str(ANCE), "--gust-half-length-m", "0"],
            "--gust-half-length-m = 0: expected a number in (0, 10000] m")
        run("land --flare-asymptote-m 10", ["land", "--aircraft", str(ANCE), "--flare-asymptote-m", "10"],
            "--flare-asymptote-m = 10: expected a height in [0, flare_height_m = 10 m)")
        run("land --turbulent-integrator euler", ["land", "--aircraft", str(ANCE), "--turbulent-integrator",
                                                  "euler"],
            "--turbulent-integrator = 'euler': expected rk4 or dopri5")
        run("run --threads 0", ["run", str(study), "-o", "{out}/out.h5", "--threads", "0"],
            "--threads = 0: expected a whole number in [1, 4096]")
        (tmp / "past.csv").write_text("height_m\n2.0\n1e999\n")
        (tmp / "past.toml").write_text(study_text("aircraft.toml", '[design]\nkind = "list"\ncsv = "past.csv"\n'))
        run("design CSV value past a double", ["run", str(tmp / "past.toml"), "-o", "{out}/out.h5"],
            "the number is past the largest magnitude a double can hold")

        # 5. One printable line: a person's text escaped; no doubled words.
        run("a study file name with an ESC sequence and broken UTF-8",
            ["run", str(tmp / "no_such_\x1b[2J_\udcce.toml"), "-o", "{out}/out.h5"], "no_such_\\x1b[2J_\\xce.toml")
        (tmp / "missing_aircraft.toml").write_text(study_text("no_such_aircraft.toml", "height_m = 2.0\n"))
        run("missing aircraft says what is missing once", ["run", str(tmp / "missing_aircraft.toml"), "-o",
                                                           "{out}/out.h5"],
            "cannot read the aircraft file: no such file", forbid=["file file"])
        (tmp / "csvdir").mkdir()
        (tmp / "csvdir.toml").write_text(study_text("aircraft.toml", '[design]\nkind = "list"\ncsv = "csvdir"\n'))
        run("design CSV is a directory", ["run", str(tmp / "csvdir.toml"), "-o", "{out}/out.h5"],
            "expected a design CSV file, found a directory", forbid=["file file"])

        # Archives: made once, then broken.
        archives = tmp / "archives"
        archives.mkdir()
        a0, s0, a1 = archives / "a0.h5", archives / "s0.h5", archives / "a1.h5"
        if not (make_archive(grid, a0) and make_archive(grid, s0, "0/2") and make_archive(grid, a1, "1/2")):
            return
        os.link(s0, archives / "s0_hard.h5")
        (archives / "s1_soft.h5").symlink_to(a1)
        run("merge -o one of its shards --force", ["merge", str(s0), str(a1), "-o", str(s0), "--force"],
            "is the shard archive")
        run("merge -o a hard link to a shard --force", ["merge", str(s0), str(a1), "-o", str(archives / "s0_hard.h5"),
                                                        "--force"], "a hard link or a symlink to it")
        run("merge -o a symlink to a shard --force", ["merge", str(s0), str(a1), "-o", str(archives / "s1_soft.h5"),
                                                      "--force"], "is the shard archive")
        if device:
            run("merge --force onto a character device", ["merge", str(s0), str(a1), "-o", str(device), "--force"],
                "is a character device, not a regular file")
            run("report -o a character device", ["report", str(a0), "-o", str(device)],
                "is a character device; expected a directory")
            run("boundary --archive of a character device", ["boundary", "--archive", str(device)],
                "is a character device, not a regular file",
                after=lambda: [f"created {device}.lock"] if os.path.exists(f"{device}.lock") else [])
        run("report -o an input archive", ["report", str(a0), "-o", str(a0)], "is the input archive")
        report_dir = tmp / "report_dir"
        report_dir.mkdir()
        shutil.copyfile(a0, report_dir / "index.html")
        run("report into a directory whose index.html is an input", ["report", str(report_dir / "index.html"), "-o",
                                                                     str(report_dir)],
            "the report would replace", protect=[report_dir])
        run("report of a FIFO", ["report", str(fifo), "-o", "{out}/r"], "is a FIFO, not a regular file", timeout=20)
        run("query of a FIFO", ["query", str(fifo)], "is a FIFO, not a regular file", timeout=20)
        run("query of a character device", ["query", "/dev/zero"], "is a character device, not a regular file",
            timeout=20)
        run("sensitivity of a FIFO", ["sensitivity", str(fifo), "--output", "x"], "is a FIFO, not a regular file",
            timeout=20)

        # 4. Archives cannot crash a reader; a damaged one is bad input (exit 2), everywhere alike.
        try:
            broken = damaged_archives(a0, archives)
        except ImportError as error:
            print(f"SKIP damaged-archive cases: {error} (python3-h5py is needed)")
            return
        for reader, args in (("query", ["query", "{a}"]), ("query --describe", ["query", "{a}", "--describe"]),
                             ("boundary --archive", ["boundary", "--archive", "{a}", "--no-write"]),
                             ("merge", ["merge", "{a}", "-o", "{out}/all.h5"]),
                             ("report", ["report", "{a}", "-o", "{out}/report"]),
                             ("sensitivity", ["sensitivity", "{a}", "--output", "stability_margin_per_s",
                                              "--no-write"])):
            for kind, fragment in (("short", "results/modes/stability_margin_per_s = 7 rows: expected one row per run"),
                                   ("no_attrs", "run_count: missing root attribute")):
                run(f"{reader} of an archive with {kind}", [a.replace("{a}", str(broken[kind])) for a in args],
                    fragment)
        run("query of an archive cut in half", ["query", str(broken["cut"])], "cut.h5")
        run("query of random bytes behind the HDF5 signature", ["query", str(broken["noise"])], "noise.h5")
        run("query of an HDF5 file of arbitrary groups", ["query", str(broken["foreign"])], "not a gesweep archive")
        run("report of an HDF5 file of arbitrary groups", ["report", str(broken["foreign"]), "-o", "{out}/r"],
            "not a gesweep archive")
        # The report script itself (run directly) validates the same way and leaves no directory.
        with tempfile.TemporaryDirectory() as out:
            result = subprocess.run(["/usr/bin/python3", str(ROOT.parent.parent / "scripts/report/report.py"), "-o",
                                     f"{out}/r", "--", str(broken["short"])], capture_output=True, text=True, timeout=120,
                                     env=dict(os.environ, GESWEEP_BINARY=GESWEEP))  # its column manifest
            global count
            count += 1
            lines = result.stderr.strip().splitlines()
            if result.returncode != 2 or len(lines) != 1 or "expected one row per run" not in lines[0] or \
                    os.path.exists(f"{out}/r"):
                failures.append(f"report.py of an archive with a short result: exit {result.returncode}, "
                                f"{len(lines)} lines, left {os.listdir(out)}: {result.stderr.strip()[:300]}")


hardening_cases()


def shard_identity_cases():
    """Issue 26: a virtual archive whose shard files were replaced, re-run for the wrong shard,
    swapped, copied over, deleted, moved, linked to the merge, taken from another study, or that
    reads itself in a cycle, refused by every reader with one line (shard_cases.py makes them); merge
    as a writer: onto a shard its input reads, onto an archive a sweep is writing; HDF5_VDS_PREFIX
    pointing at the wrong file."""
    import fcntl
    import shard_cases
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        try:
            cases = shard_cases.make(GESWEEP, tmp / "cases")
        except RuntimeError as error:
            failures.append(f"shard identity cases could not be made: {error}")
            return
        every_reader = {"shard re-run for the wrong shard over another's file", "a shard deleted",
                        "a cycle of two virtual archives"}
        for case in cases:
            readers = shard_cases.READERS if case.name in every_reader else shard_cases.READERS[:1]
            for reader, args in readers:
                with tempfile.TemporaryDirectory() as out:
                    check(f"{reader} of a virtual archive: {case.name}",
                          [a.replace("{a}", case.archive).replace("{out}", out) for a in args], case.fragment, out,
                          protect=case.protect)
        made = tmp / "cases" / "base"
        shards = [str(made / "s0.h5"), str(made / "s1.h5")]
        protect = shards + [str(made / "merged.h5")]
        with tempfile.TemporaryDirectory() as out:
            check("merge of a virtual archive -o one of its shards --force",
                  ["merge", str(made / "merged.h5"), "-o", shards[0], "--force"],
                  f"is the shard file {shards[0]} that the input {made / 'merged.h5'} reads", out, protect=protect)
        # A sweep writing the output holds OUTPUT.lock (flock, as gesweep run takes it).
        with tempfile.TemporaryDirectory() as out:
            live = pathlib.Path(out) / "live.h5"
            live.write_bytes(b"the archive a sweep is writing")
            with open(str(live) + ".lock", "w") as lock:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                check("merge --force onto an archive a sweep is writing", ["merge", *shards, "-o", str(live), "--force"],
                      "archive in use: another gesweep process is writing it", out, keep=["live.h5", "live.h5.lock"],
                      protect=protect)
        # HDF5_VDS_PREFIX honoured: a file of that name found there first is the one checked.
        prefix = tmp / "prefix"
        prefix.mkdir()
        shutil.copyfile(made / "s1.h5", prefix / "s0.h5")
        os.environ["HDF5_VDS_PREFIX"] = str(prefix)
        try:
            with tempfile.TemporaryDirectory() as out:
                check("query with HDF5_VDS_PREFIX naming another shard's file", ["query", str(made / "merged.h5")],
                      f"shard file {prefix / 's0.h5'} holds runs 4..7 of 8 (shard 1/2), expected runs 0..3", out,
                      protect=protect + [str(prefix / "s0.h5")])
        finally:
            del os.environ["HDF5_VDS_PREFIX"]


def integer_cases():
    """Issue 26, item 3: seeds, run indices and counts parsed exactly at every entry point
    (integer_cases.py)."""
    import integer_cases as made
    with tempfile.TemporaryDirectory() as tmp:
        for case in made.cases(pathlib.Path(tmp) / "inputs"):
            with tempfile.TemporaryDirectory() as out:
                check(case.name, case.args, case.fragment, out)


sys.path.insert(0, str(ROOT))
shard_identity_cases()
integer_cases()


def damaged_archive_cases():
    """Issue 26, item 8 (damaged_cases.py): the eight files on which libhdf5 1.10.8 itself hangs or
    crashes, through `query --describe`, `merge`, `run --resume` (and one of each kind through
    `boundary --archive`, `sensitivity`, `dispersion`, `report`): one line naming the file, exit 2,
    within 5 s, bytes unchanged; `run --resume` onto files that are not a resumable archive of its
    study (truncated, cut short, empty, text, flipped bytes): refused, the file byte for byte as it was."""
    import damaged_cases
    seconds = damaged_cases.SECONDS_SANITIZED if SANITIZED else damaged_cases.SECONDS

    def unchanged(path, digest):
        return lambda: [] if damaged_cases.sha256(path) == digest else [f"{path}: sha256 changed"]

    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        try:
            defects = damaged_cases.defect_files(tmp / "defects")
            study, targets = damaged_cases.resume_targets(GESWEEP, tmp / "resume")
        except (RuntimeError, AssertionError) as error:
            failures.append(f"damaged archive cases could not be made: {error}")
            return
        for name, path in defects.items():
            digest = damaged_cases.sha256(path)
            # The file first; the guard's words where libhdf5 breaks the same way every time.
            fragment = f"{path}: libhdf5 " if name in damaged_cases.ALWAYS_BREAKS else f"{path}: "
            for reader, args in (("query --describe", ["query", str(path), "--describe"]),
                                 ("merge", ["merge", str(path), "-o", "{out}/merged.h5"]),
                                 ("run --resume", ["run", str(study), "-o", str(path), "--resume", "-q"])):
                with tempfile.TemporaryDirectory() as out:
                    check(f"{reader} of {name} (libhdf5 hangs or crashes on it)",
                          [a.replace("{out}", out) for a in args], fragment, out, timeout=seconds,
                          after=unchanged(path, digest))
        # The other readers, on one file of each kind (a loop, a crash, a bad free): the same guard.
        for name in damaged_cases.ONE_OF_EACH:
            path = defects[name]
            digest = damaged_cases.sha256(path)
            fragment = f"{path}: libhdf5 " if name in damaged_cases.ALWAYS_BREAKS else f"{path}: "
            for reader, args in damaged_cases.OTHER_READERS:
                with tempfile.TemporaryDirectory() as out:
                    check(f"{reader} of {name} (libhdf5 hangs or crashes on it)",
                          [a.replace("{a}", str(path)).replace("{out}", out) for a in args], fragment, out,
                          timeout=seconds, after=unchanged(path, digest))
        for name, path, fragment in targets:
            digest = damaged_cases.sha256(path)
            with tempfile.TemporaryDirectory() as out:
                check(f"run --resume onto {name}", ["run", str(study), "-o", str(path), "--resume", "-q"],
                      fragment, out, timeout=seconds, after=unchanged(path, digest))


damaged_archive_cases()


def bounded_work_cases():
    """Issue 26, items 5 and 6 (bounded_cases.py): runs of 1e9 noise samples refused up front (study, dry
    run, flags; within a second, under a 1 GB address-space limit), dispersion's tail probability and
    confidence level past their range, `run -o` into a read-only directory, a constant column."""
    import time
    import bounded_cases
    with tempfile.TemporaryDirectory() as tmp:
        try:
            cases = bounded_cases.noise_cases(tmp) + bounded_cases.dispersion_cases(GESWEEP, tmp)
        except RuntimeError as error:
            failures.append(f"bounded work cases could not be made: {error}")
            return
        directory, words = bounded_cases.read_only_directory(tmp)
        if directory is None:
            print(f"SKIP run -o into a read-only directory: {words}")
        else:
            cases.append(bounded_cases.read_only_case(tmp, directory, words))
        try:
            for case in cases:
                options = dict(case.kwargs)
                within_s = options.pop("within_s", None)
                with tempfile.TemporaryDirectory() as out:
                    started = time.monotonic()
                    check(case.name, [a.replace("{out}", out) for a in case.args], case.fragment, out, **options)
                    elapsed = time.monotonic() - started
                if within_s is not None and elapsed > within_s:
                    failures.append(f"{case.name}: took {elapsed:.2f} s, expected a refusal within {within_s} s")
        finally:
            bounded_cases.release_read_only(directory)
        problems = bounded_cases.constant_column_problems(GESWEEP, tmp)
        failures.extend(problems)


bounded_work_cases()

for failure in failures:
    print("FAIL", failure)
print(f"{count} hostile inputs, {count - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures or count == 0 else 0)
