"""gesweep.run and gesweep.open_archive: the sweep through the module, the archive as xarray reads it
against h5py (the README's snippet), the grid reshape on a non-square three-axis grid, and a sweep
stopped by KeyboardInterrupt and completed with resume=True, equal bit for bit to one run straight."""
import os
import pathlib
import signal
import subprocess

import h5py
import numpy as np
import pytest

from conftest import ROOT, cli

HERE = pathlib.Path(__file__).resolve().parent


def test_stability_map_equals_the_readme_snippet(gesweep, tmp_path):
    archive = tmp_path / "stability_map.h5"
    summary = gesweep.run(ROOT / "studies" / "stability_map.toml", archive)
    assert summary["runs_ok"] == 96000 and summary["runs_failed"] == 0 and not summary["cancelled"]
    # The README's five lines of h5py.
    f = h5py.File(archive, "r")
    ok = f["runs/status"][:] == 1
    H, u = f["design/height_m"][:][ok], f["design/speed_mps"][:][ok]
    sigma = f["results/modes/stability_margin_per_s"][:][ok]
    ds = gesweep.open_archive(archive)
    assert ds.stability_margin_per_s.dims == ("speed_mps", "height_m")
    assert ds.stability_margin_per_s.shape == (160, 600)
    assert ds.stability_margin_per_s.attrs["units"] == f["results/modes/stability_margin_per_s"].attrs["units"]
    # Height fastest: C order of (speed, height).
    np.testing.assert_array_equal(ds.stability_margin_per_s.values.ravel(), sigma)
    grid_u, grid_h = np.meshgrid(ds.speed_mps.values, ds.height_m.values, indexing="ij")
    np.testing.assert_array_equal(grid_u.ravel(), u)
    np.testing.assert_array_equal(grid_h.ravel(), H)
    # The selection of the issue, and a plot of it.
    column = ds.stability_margin_per_s.sel(speed_mps=32, method="nearest")
    j = int(np.argmin(np.abs(ds.speed_mps.values - 32)))
    np.testing.assert_array_equal(column.values, sigma.reshape(160, 600)[j])
    import matplotlib
    matplotlib.use("Agg")
    column.plot()
    eig = ds.eigenvalues.isel(speed_mps=3, height_m=7).values
    raw = f["results/modes/eigenvalues"][3 * 600 + 7]
    np.testing.assert_array_equal(eig, raw["re"] + 1j * raw["im"])
    f.close()
    ds.close()


def test_open_is_lazy(gesweep, tmp_path):
    archive = tmp_path / "grid3.h5"
    gesweep.run(HERE / "grid3.toml", archive, threads=1)
    ds = gesweep.open_archive(archive)
    from xarray.core import indexing
    variable = ds.variables["stability_margin_per_s"]
    assert isinstance(variable._data, indexing.LazilyIndexedArray)  # nothing read yet
    ds.close()


def test_grid_reshape_on_three_axes(gesweep, ance, tmp_path):
    archive = tmp_path / "grid3.h5"
    gesweep.run(HERE / "grid3.toml", archive, threads=2)
    ds = gesweep.open_archive(archive)
    sigma = ds.stability_margin_per_s
    assert sigma.dims == ("speed_mps", "height_m", "h_derivatives")
    assert sigma.shape == (3, 4, 2)
    np.testing.assert_array_equal(ds.speed_mps.values, [28.0, 40.0, 55.0])
    np.testing.assert_array_equal(ds.height_m.values, [1.0, 2.0, 4.0, 9.0])
    assert ds.eigenvalues.dims == ("speed_mps", "height_m", "h_derivatives", "eigenvalue")
    # Each cell is the run of its coordinates: sigma recomputed there (gesweep.modes, at that cell's
    # speed, height and option) equals the cell.
    for option_index, option in enumerate(ds.h_derivatives.values):
        expected = gesweep.modes(ance, ds.height_m.values[None, :], ds.speed_mps.values[:, None],
                                 h_derivatives=bool(option))["stability_margin_per_s"]
        np.testing.assert_array_equal(sigma.values[:, :, option_index], expected)
    # Outer and scalar selections read the right rows.
    np.testing.assert_array_equal(sigma.isel(speed_mps=[0, 2], h_derivatives=1).values,
                                  sigma.values[[0, 2], :, 1])
    assert sigma.isel(speed_mps=1, height_m=2, h_derivatives=0).values == sigma.values[1, 2, 0]
    ds.close()


def test_failed_and_pending_runs_are_masked(gesweep, tmp_path):
    archive = tmp_path / "grid3.h5"
    gesweep.run(HERE / "grid3.toml", archive)
    with h5py.File(archive, "r+") as f:  # pretend two runs are not complete: pending and failed
        status = f["runs/status"]
        status[5] = 0
        status[6] = 2
    ds = gesweep.open_archive(archive)
    flat = ds.stability_margin_per_s.values.ravel()
    assert np.isnan(flat[5]) and np.isnan(flat[6]) and np.isfinite(np.delete(flat, [5, 6])).all()
    assert np.isnan(ds.stable.values.ravel()[5])
    assert ds.status.values.ravel()[6] == 2
    ds.close()


def test_run_refuses_an_existing_archive_with_the_python_remedy(gesweep, tmp_path):
    archive = tmp_path / "grid3.h5"
    gesweep.run(HERE / "grid3.toml", archive)
    with pytest.raises(gesweep.InputError) as error:
        gesweep.run(HERE / "grid3.toml", archive)
    assert "resume=True" in str(error.value) and "force=True" in str(error.value)
    assert isinstance(error.value, ValueError)
    again = gesweep.run(HERE / "grid3.toml", archive, force=True)
    assert again["runs_ok"] == 24


def test_reads_a_merged_virtual_archive(gesweep, tmp_path):
    shards = []
    for i in range(2):
        shards.append(tmp_path / f"shard{i}.h5")
        gesweep.run(HERE / "grid3.toml", shards[-1], shard=f"{i}/2")
    merged = tmp_path / "merged.h5"
    cli("merge", *shards, "-o", merged)
    whole = tmp_path / "whole.h5"
    gesweep.run(HERE / "grid3.toml", whole)
    a, b = gesweep.open_archive(merged), gesweep.open_archive(whole)
    assert a.stability_margin_per_s.dims == b.stability_margin_per_s.dims
    np.testing.assert_array_equal(a.stability_margin_per_s.values, b.stability_margin_per_s.values)
    a.close()
    b.close()
    # A shard alone is a slice of the grid: a run dimension.
    s = gesweep.open_archive(shards[1])
    assert s.stability_margin_per_s.dims == ("run",) and "speed_mps" in s.coords
    s.close()


def _datasets(path):
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and not name.startswith("analysis"):
                out[name] = obj[()].tobytes()
        f.visititems(visit)
    return out


def test_keyboard_interrupt_then_resume_is_bit_identical(gesweep, tmp_path):
    study = HERE / "interrupt.toml"
    stopped = tmp_path / "stopped.h5"
    seen = []

    def progress(done, to_do):
        seen.append(done)
        if done > 0 and len(seen) < 1000:
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C, while the sweep runs

    with pytest.raises(KeyboardInterrupt):
        gesweep.run(study, stopped, threads=2, progress=progress)
    with h5py.File(stopped, "r") as f:
        status = f["runs/status"][:]
    assert (status == 0).any() and (status == 1).any(), "the interrupt was to land mid-sweep"
    resumed = gesweep.run(study, stopped, threads=1, resume=True)
    assert resumed["runs_pending"] == 0 and 0 < resumed["runs_run"] < 1200
    straight = tmp_path / "straight.h5"
    gesweep.run(study, straight, threads=2)
    a, b = _datasets(stopped), _datasets(straight)
    assert a.keys() == b.keys()
    for name in a:
        assert a[name] == b[name], name


def test_analysis_products_as_datasets(gesweep, tmp_path):
    archive = tmp_path / "grid3.h5"
    gesweep.run(HERE / "grid3.toml", archive)
    cli("boundary", "--archive", archive)
    assert "boundary" in gesweep.list_products(archive)
    with h5py.File(archive, "r") as f:
        raw = {name: f["analysis/boundary"][name][()] for name in f["analysis/boundary"]
               if isinstance(f["analysis/boundary"][name], h5py.Dataset)}
    product = gesweep.open_archive(archive, product="boundary")
    for name, values in raw.items():
        if values.dtype.kind == "f":
            np.testing.assert_array_equal(product[name].values, values, err_msg=name)
    product.close()
    with pytest.raises(gesweep.InputError, match="product = nothing: expected one of"):
        gesweep.open_archive(archive, product="nothing")
