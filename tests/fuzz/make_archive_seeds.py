#!/usr/bin/python3
"""Seeds for the fuzz_archive target (tests/fuzz/archive_fuzz.cc), written into OUT_DIR:

    /usr/bin/python3 tests/fuzz/make_archive_seeds.py GESWEEP OUT_DIR

The target's first byte chooses how the rest is used: even, the bytes of a file; odd, a program that
builds an HDF5 file. Seeds of the first kind: archives gesweep writes for three small studies (modes
on a grid, an open loop with time series, a Sobol design), the same cut short and with bytes
flipped, and files h5py writes as another program would (arbitrary groups and datasets, a gesweep
format attribute without the rest, a results dataset shorter than runs/status, strings where numbers
belong, a variable-length runs/message). Seeds of the second kind: a few fixed byte strings."""
import os
import pathlib
import random
import subprocess
import sys
import tempfile

import h5py
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
ANCE = ROOT / "studies" / "aircraft" / "ance.toml"

STUDIES = {
    "modes_grid": f'''format_version = 1
name = "seed_modes"
aircraft = "{ANCE}"
[analyses.modes]
[analyses.boundary]
[output]
chunk_runs = 4
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
linspace = [1.0, 6.0, 6]
[[design.parameter]]
name = "speed_mps"
values = [30.0, 34.0]
''',
    "open_loop_series": f'''format_version = 1
name = "seed_open_loop"
aircraft = "{ANCE}"
[analyses.open_loop]
duration_s = 2.0
[parameters]
speed_mps = 32.0
[output]
time_series = true
output_dt_s = 0.5
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
values = [2.0, 5.0, 9.0]
''',
    "sobol": '''format_version = 1
name = "seed_sobol"
[analyses.ishigami]
[design]
kind = "sobol"
base_samples = 4
[[design.parameter]]
name = "x1"
uniform = [-3.14, 3.14]
[[design.parameter]]
name = "x2"
uniform = [-3.14, 3.14]
''',
}


def write_seed(out, name, data, mode=0):
    (out / name).write_bytes(bytes([mode]) + data)


def h5py_files(work):
    """Files another program could write."""
    files = {}
    path = work / "foreign.h5"
    with h5py.File(path, "w") as f:
        f.create_group("a/b/c")
        f["a/x"] = np.arange(7.0)
        f["a/b/s"] = np.array([b"one", b"two"])
        f.attrs["title"] = "not a gesweep archive"
    files["foreign"] = path
    path = work / "format_only.h5"
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "gesweep-archive"
        f.attrs["format_version"] = 1
    files["format_only"] = path
    for name, short, message_vlen, design_text in (("short_result", True, False, False),
                                                    ("vlen_message", False, True, False),
                                                    ("text_design", False, False, True)):
        path = work / f"{name}.h5"
        runs = 5
        with h5py.File(path, "w") as f:
            for key, value in (("format", "gesweep-archive"), ("format_version", 1), ("run_count", runs),
                               ("design_runs", runs), ("first_run", 0), ("chunk_runs", 4)):
                f.attrs[key] = value
            f["runs/index"] = np.arange(runs, dtype=np.int64)
            f["runs/id"] = np.arange(runs, dtype=np.uint64)
            f["runs/status"] = np.ones(runs, dtype=np.int8)
            if message_vlen:
                f.create_dataset("runs/message", data=["m"] * runs, dtype=h5py.string_dtype())
            else:
                f["runs/message"] = np.array([b""] * runs, dtype="S16")
            f.create_group("design").attrs["parameters"] = ["height_m"]
            f["design/height_m"] = np.array([b"1"] * runs) if design_text else np.linspace(1, 5, runs)
            f["results/modes/stability_margin_per_s"] = np.zeros(runs - 1 if short else runs)
        files[name] = path
    return files


def main():
    gesweep, out = sys.argv[1], pathlib.Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    rng = random.Random(20261201)
    with tempfile.TemporaryDirectory() as work:
        work = pathlib.Path(work)
        archives = {}
        for name, text in STUDIES.items():
            study = work / f"{name}.toml"
            study.write_text(text)
            archive = work / f"{name}.h5"
            subprocess.run([gesweep, "run", str(study), "-o", str(archive), "-q", "--threads", "1"], check=True)
            archives[name] = archive
        archives.update(h5py_files(work))
        for name, path in archives.items():
            data = path.read_bytes()
            write_seed(out, f"seed_{name}", data)
            write_seed(out, f"seed_{name}_half", data[:len(data) // 2])
            write_seed(out, f"seed_{name}_cut", data[:max(8, len(data) - 512)])
            flipped = bytearray(data)
            for _ in range(8):
                flipped[rng.randrange(len(flipped))] ^= 1 << rng.randrange(8)
            write_seed(out, f"seed_{name}_flipped", bytes(flipped))
        write_seed(out, "seed_signature_then_noise", b"\x89HDF\r\n\x1a\n" + bytes(rng.randrange(256) for _ in range(600)))
        for k in range(6):
            write_seed(out, f"seed_program_{k}", bytes(rng.randrange(256) for _ in range(64 + 64 * k)), mode=1)
    print(f"{len(list(out.iterdir()))} seeds in {out}")


if __name__ == "__main__":
    main()
