#!/usr/bin/python3
"""`gesweep risk --mpi`: the landing risk by subset simulation on MPI ranks (docs/dispersion.md, "On
MPI ranks"; docs/cluster.md, "The landing risk on MPI ranks").

  risk_mpi_test.py --gesweep build/gesweep --mpirun mpiexec

The oracle is the same study run by one process on one thread (an identity, not a number the code
under test produced): the ranks must not change what is estimated, only who flies the landings.
1. 3 oversubscribed ranks and 2 ranks (`--threads 1` each): the archive equals the single-process one
   dataset by dataset and attribute by attribute, bit for bit, provenance (command line, study path)
   excluded (tests/slurm/compare_archives.py); `gesweep dispersion ARCHIVE --format json` prints the
   same JSON (the archive's path aside); the table is printed once; every rank flew landings and
   the landings per rank add up to the archive's.
2. SIGTERM to mpirun during level 2 (mpirun forwards it to every rank): every rank stops (exit 143;
   mpirun's own code is 1 after a forwarded signal), one "stopped" line, no archive, the journal
   kept; `--resume` under 3 ranks finishes to the reference archive, bit for bit. Then a run of 3
   ranks SIGKILLed (mpirun and every rank) during its second limit, and `--resume` under 2 ranks: the
   same.
3. Bad input under MPI: one line from rank 0, exit 2, nothing written: p0 = 1.5 in the study, an
   existing archive, --resume without a journal, --replay with --mpi.
Exit 0 pass, 1 fail.
"""

import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
COMPARE = ROOT / "tests" / "slurm" / "compare_archives.py"
sys.path[:0] = [str(ROOT / "tests" / "risk"), str(ROOT / "tests" / "mpi")]
# The small study of tests/risk (a turbulent landing from 30 m, about 1 ms of CPU each; a firm-landing
# limit of a few per cent, two levels, and one no landing reaches, the level cap: 940 landings at
# N = 200, about a second of CPU), its checks, and mpi_test's environment and killing of every rank.
from risk_cli_test import check, failures, write_study  # noqa: E402
from mpi_test import MPI_ENV, kill_every_rank  # noqa: E402

TIMEOUT_S = 300  # a run takes seconds; this only catches a hang


def env():
    e = dict(os.environ)
    e.update(MPI_ENV)
    return e


def gesweep(args, *more):
    return subprocess.run([args.gesweep, *map(str, more)], capture_output=True, text=True, timeout=TIMEOUT_S)


def mpi_command(args, ranks, study, out, *more):
    return [args.mpirun, "--allow-run-as-root", "--oversubscribe", "-n", str(ranks), args.gesweep, "risk",
            str(study), "-o", str(out), "--mpi", "--threads", "1", *map(str, more)]


def mpi_risk(args, ranks, study, out, *more):
    return subprocess.run(mpi_command(args, ranks, study, out, *more), capture_output=True, text=True,
                          env=env(), timeout=TIMEOUT_S)


def same_archive(reference, candidate):
    r = subprocess.run(["/usr/bin/python3", str(COMPARE), str(reference), str(candidate)], capture_output=True,
                       text=True)
    return r.returncode == 0, r.stdout + r.stderr


def dispersion_json(args, archive):
    r = gesweep(args, "dispersion", archive, "--format", "json")
    check(r.returncode == 0, f"dispersion {archive} exits 0: {r.stderr}")
    j = json.loads(r.stdout) if r.returncode == 0 else {}
    j.pop("archive", None)
    return j


def gesweep_lines(stderr, prefix):
    return [line for line in stderr.splitlines() if line.startswith(prefix)]


def check_ranks(args, study, reference, tmp):
    """Section 1: 3 and 2 ranks against one process."""
    expected = dispersion_json(args, reference)
    for ranks in (3, 2):
        out = tmp / f"ranks{ranks}.h5"
        r = mpi_risk(args, ranks, study, out)
        check(r.returncode == 0, f"{ranks} ranks exit 0: {r.returncode}\n{r.stderr}")
        if r.returncode != 0:
            continue
        equal, diff = same_archive(reference, out)
        check(equal, f"{ranks} ranks: the single-process archive, dataset by dataset:\n{diff}")
        check(dispersion_json(args, out) == expected, f"{ranks} ranks: the same dispersion JSON")
        check(r.stdout.count("# subset simulation") == 1, f"{ranks} ranks: the table printed once:\n{r.stdout}")
        spread = gesweep_lines(r.stderr, "gesweep: ") and [l for l in r.stderr.splitlines() if "per rank:" in l]
        check(len(spread) == 1, f"{ranks} ranks: one line of landings per rank:\n{r.stderr}")
        if spread:
            per_rank = [int(x) for x in spread[0].rsplit("per rank:", 1)[1].strip(" )").split()]
            runs = expected["runs"]
            check(len(per_rank) == ranks and min(per_rank) > 0 and sum(per_rank) == runs,
                  f"{ranks} ranks: every rank flew landings, {runs} in all: {per_rank}")
        print(f"{ranks} ranks: the single-process archive and estimate, bit for bit ({spread})")


def run_until(args, ranks, study, out, marker, sig):
    """Starts an MPI run and sends `sig` to mpirun once rank 0's progress shows `marker`."""
    p = subprocess.Popen(mpi_command(args, ranks, study, out), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=env(), start_new_session=True)
    seen = False
    for line in p.stderr:
        if marker in line:
            seen = True
            if sig == signal.SIGKILL:
                os.killpg(os.getpgid(p.pid), signal.SIGKILL)
                kill_every_rank(str(out))
            else:
                p.send_signal(sig)
            break
    rest = p.communicate(timeout=TIMEOUT_S)[1]
    return p.returncode, seen, rest


def check_resume(args, study, reference, tmp):
    """Section 2: SIGTERM, then SIGKILL, each followed by --resume under MPI."""
    cut = tmp / "cut.h5"
    journal = pathlib.Path(str(cut) + ".journal")
    code, seen, stderr = run_until(args, 3, study, cut, "level 1 done", signal.SIGTERM)
    check(seen, f"SIGTERM: the run reached level 2:\n{stderr}")
    # Every rank exits 143; mpirun itself, signalled, exits 1 (OpenMPI) or with the ranks' code.
    check(code in (143, 1), f"SIGTERM under MPI stops it: exit {code}\n{stderr}")
    check(len(gesweep_lines(stderr, "gesweep: stopped by signal 15")) == 1, f"one 'stopped' line:\n{stderr}")
    check(not cut.exists() and journal.exists(), "a stopped MPI run leaves its journal and no archive")
    r = mpi_risk(args, 3, study, cut, "--resume")
    check(r.returncode == 0, f"--resume under 3 ranks exits 0: {r.returncode}\n{r.stderr}")
    if r.returncode == 0:
        equal, diff = same_archive(reference, cut)
        check(equal, f"SIGTERM + --resume under MPI: the single-process archive:\n{diff}")
        check(not journal.exists(), "a finished MPI run removes its journal")
    print("SIGTERM under MPI (exit 143) and --resume under 3 ranks: the single-process archive")

    killed = tmp / "killed.h5"
    journal = pathlib.Path(str(killed) + ".journal")
    code, seen, _ = run_until(args, 3, study, killed, "> 30: level 1 done", signal.SIGKILL)
    check(seen and journal.exists() and not killed.exists(),
          f"SIGKILL during the second limit leaves a journal and no archive (exit {code})")
    r = mpi_risk(args, 2, study, killed, "--resume")
    check(r.returncode == 0, f"--resume after SIGKILL under 2 ranks exits 0: {r.returncode}\n{r.stderr}")
    check("resuming from" in r.stderr, f"the resumed run says so:\n{r.stderr}")
    if r.returncode == 0:
        equal, diff = same_archive(reference, killed)
        check(equal, f"SIGKILL + --resume under MPI: the single-process archive:\n{diff}")
    print("SIGKILL under MPI and --resume under 2 ranks: the single-process archive")


def check_bad_input(args, study, reference, tmp):
    """Section 3: one line from rank 0, exit 2, nothing written."""
    bad_study = write_study(tmp, "bad_p0.toml", subset="level_probability = 1.5\nsamples_per_level = 100")
    before = reference.read_bytes()
    cases = {
        "p0 = 1.5": (bad_study, tmp / "bad.h5", (), "level_probability"),
        "an existing archive": (study, reference, (), "-o"),
        "--resume without a journal": (study, tmp / "none.h5", ("--resume",), "--resume"),
        "--replay with --mpi": (study, tmp / "replay.h5", ("--replay", "3"), "--mpi"),
    }
    for name, (path, out, more, key) in cases.items():
        r = mpi_risk(args, 3, path, out, *more)
        errors = gesweep_lines(r.stderr, "gesweep:")
        check(r.returncode == 2, f"{name} under MPI exits 2: {r.returncode}\n{r.stderr}")
        check(len(errors) == 1 and errors[0].startswith("gesweep: error:") and key in errors[0],
              f"{name} under MPI: one line naming {key}: {errors}")
        if out != reference:
            check(not out.exists() and not pathlib.Path(str(out) + ".journal").exists(),
                  f"{name}: nothing written")
    check(reference.read_bytes() == before, "the existing archive is untouched")
    print("bad input under MPI: one line each, exit 2, nothing written")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gesweep", required=True)
    parser.add_argument("--mpirun", default="mpirun")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="gesweep-risk-mpi-") as tmp:
        tmp = pathlib.Path(tmp)
        study = write_study(tmp, "risk.toml", n=200, levels=3)
        reference = tmp / "reference.h5"
        r = gesweep(args, "risk", study, "-o", reference, "--threads", 1)
        if r.returncode != 0:
            print(f"FAIL: the single-process reference run exits {r.returncode}:\n{r.stderr}")
            return 1
        check_ranks(args, study, reference, tmp)
        check_resume(args, study, reference, tmp)
        check_bad_input(args, study, reference, tmp)
    if failures:
        print(f"FAIL: {len(failures)} check(s)")
        return 1
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
