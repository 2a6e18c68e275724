#!/usr/bin/python3
"""The netCDF view of an archive (schemas/archive.md, "netCDF view"): netCDF-4 readers see named
dimensions, not invented ones.

  netcdf_view_test.py REPO_ROOT GESWEEP_BINARY

A small sweep (modes, open_loop with time series), run whole and as 2 shards merged virtually and by
copy. For each archive, xarray's h5netcdf engine (Debian's python3-h5netcdf) opens results/modes,
series/open_loop, runs and design with dimensions named `run`, `modes_eigenvalues_index` and `time_s`
(a coordinate), without phony dimensions, and every value equals h5py's; `ncdump -h` (netcdf-bin)
lists the same named dimensions.
"""
import pathlib
import re
import subprocess
import sys
import tempfile

import h5py
import numpy as np
import xarray

root, binary = pathlib.Path(sys.argv[1]).resolve(), sys.argv[2]

SPEEDS, HEIGHTS = 3, 5        # the grid: RUNS runs
RUNS = SPEEDS * HEIGHTS
DURATION_S, OUTPUT_DT_S = 2.0, 0.1
SAMPLES = round(DURATION_S / OUTPUT_DT_S) + 1  # 0, dt, ..., duration: the time axis's length
EIGENVALUES = 5               # Eq. (1) has five states (docs/model.md): short period 2, phugoid 2, height 1


def gesweep(*args):
    result = subprocess.run([binary, *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, f"gesweep {' '.join(map(str, args))}: exit {result.returncode}\n{result.stderr}"


def open_group(path, group):
    # phony_dims unset: h5netcdf raises on any axis without a dimension scale.
    return xarray.open_dataset(path, engine="h5netcdf", group=group)


def check(path, runs):
    with h5py.File(path, "r") as f:
        modes = open_group(path, "results/modes")
        assert dict(modes.sizes) == {"run": runs, "modes_eigenvalues_index": EIGENVALUES}, dict(modes.sizes)
        assert modes["eigenvalues"].dims == ("run", "modes_eigenvalues_index")
        for name in ("stability_margin_per_s", "stable", "classification"):
            assert modes[name].dims == ("run",), (name, modes[name].dims)
            expected = f[f"results/modes/{name}"][:]
            assert np.array_equal(modes[name].values, expected, equal_nan=True), name
        eigenvalues = f["results/modes/eigenvalues"][:]
        got = modes["eigenvalues"].values
        if got.dtype.names:  # h5netcdf gives the compound {re, im} as a structured array
            got = got["re"] + 1j * got["im"]
        assert np.array_equal(got, eigenvalues["re"] + 1j * eigenvalues["im"] if eigenvalues.dtype.names
                              else eigenvalues, equal_nan=True)
        # The design columns are coordinates of `run` in every results group (hard links to design/*,
        # named by CF's `coordinates` attribute): the same objects, so the same values.
        for name in ("speed_mps", "height_m"):
            assert name in modes.coords and modes[name].dims == ("run",), (name, list(modes.coords))
            assert np.array_equal(modes[name].values, f[f"design/{name}"][:]), name
            assert f[f"results/modes/{name}"] == f[f"design/{name}"], name  # a link, not a copy
        picked = modes["stability_margin_per_s"].where(
            (modes.speed_mps == f["design/speed_mps"][0]) & (modes.height_m == f["design/height_m"][0]), drop=True)
        assert picked.size == 1 and picked.values[0] == f["results/modes/stability_margin_per_s"][0]
        modes.close()

        series = open_group(path, "series/open_loop")
        assert dict(series.sizes) == {"run": runs, "time_s": SAMPLES}, dict(series.sizes)
        assert "time_s" in series.coords and series["time_s"].dims == ("time_s",)
        assert np.array_equal(series["time_s"].values, f["series/open_loop/time_s"][:])
        assert np.allclose(series["time_s"].values, np.arange(SAMPLES) * OUTPUT_DT_S, rtol=0, atol=1e-12)
        assert series["height_m"].dims == ("run", "time_s")
        assert np.array_equal(series["height_m"].values, f["series/open_loop/height_m"][:], equal_nan=True)
        # series/open_loop/height_m and speed_mps are trajectories: the design's columns of the same
        # names are not linked over them (and so are not coordinates there).
        for name in ("speed_mps", "height_m"):
            assert name not in series.coords and f[f"series/open_loop/{name}"] != f[f"design/{name}"], name
        series.close()

        runs_group = open_group(path, "runs")
        for name in ("index", "id", "status"):
            assert runs_group[name].dims == ("run",), (name, runs_group[name].dims)
            assert np.array_equal(runs_group[name].values, f[f"runs/{name}"][:]), name
        assert sorted(runs_group["index"].values) == list(range(runs))
        runs_group.close()

        design = open_group(path, "design")
        assert dict(design.sizes) == {"run": runs}
        for name in ("speed_mps", "height_m"):
            assert np.array_equal(design[name].values, f[f"design/{name}"][:]), name
        design.close()

        # The dimensions without values are not variables for netCDF.
        whole = xarray.open_dataset(path, engine="h5netcdf")
        assert "run" not in whole.variables and "modes_eigenvalues_index" not in whole.variables
        whole.close()

    header = subprocess.run(["ncdump", "-h", str(path)], capture_output=True, text=True)
    assert header.returncode == 0, header.stderr
    text = header.stdout
    assert re.search(rf"\brun = {runs} ;", text), text[:2000]
    assert re.search(rf"\bmodes_eigenvalues_index = {EIGENVALUES} ;", text), text[:2000]
    assert re.search(rf"\btime_s = {SAMPLES} ;", text), text[:2000]
    assert re.search(r"stability_margin_per_s\(run\) ;", text)
    assert re.search(r"height_m\(run, time_s\) ;", text)
    assert "phony_dim" not in text, [line for line in text.splitlines() if "phony_dim" in line][:5]


with tempfile.TemporaryDirectory() as directory:
    work = pathlib.Path(directory)
    study = work / "s.toml"
    study.write_text(f"""format_version = 1
name = "netcdf_view"
aircraft = "{root / 'studies' / 'aircraft' / 'ance.toml'}"
[analyses.modes]
[analyses.open_loop]
duration_s = {DURATION_S}
step_s = 0.01
[output]
chunk_runs = 4
time_series = true
output_dt_s = {OUTPUT_DT_S}
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [28.0, 40.0, {SPEEDS}]
[[design.parameter]]
name = "height_m"
linspace = [0.8, 6.0, {HEIGHTS}]
""")
    single = work / "single.h5"
    gesweep("run", study, "-o", single, "-q")
    check(single, RUNS)
    shards = [work / f"shard-{i}.h5" for i in range(2)]
    for i, shard in enumerate(shards):
        gesweep("run", study, "-o", shard, "--shard", f"{i}/2", "-q")
    check(shards[0], h5py.File(shards[0], "r")["runs/status"].shape[0])
    virtual, copy = work / "virtual.h5", work / "copy.h5"
    gesweep("merge", *shards, "-o", virtual, "-q")
    gesweep("merge", *shards, "-o", copy, "--copy", "-q")
    for merged in (virtual, copy):
        check(merged, RUNS)
print("netCDF view: named dimensions in the whole, shard, virtual and copied archives")
