#!/usr/bin/python3
"""Worker-compressed chunks read back through plain HDF5 and through an independent decoder.

  worker_chunks_test.py REPO_ROOT GESWEEP_BINARY

The workers of `gesweep run` filter their own chunks (shuffle, deflate, Fletcher-32) and the writer
stores them with H5Dwrite_chunk (docs/sweep.md). This test, with nothing but Debian's python3-h5py
and numpy:
  1. runs a study on 2 threads (modes + a short open loop with time series, batches of 32 runs, the
     last batch partial);
  2. checks every per-run dataset declares the standard filters h5py and h5dump know (gzip,
     shuffle for multi-byte types, fletcher32);
  3. decodes every stored chunk without HDF5's filters (h5py's read_direct_chunk, then its own
     Fletcher-32, Python's zlib, numpy's unshuffle) and requires the values HDF5 decodes;
  4. compares the values with what the engine computes for the same runs in another process
     (`gesweep modes --format json`: eigenvalues and stability margin, bit for bit);
  5. reads the archive with h5dump (the stock tool) and pandas-style whole-column reads.
"""
import json
import pathlib
import subprocess
import sys
import tempfile
import zlib

import h5py
import numpy as np

root, binary = pathlib.Path(sys.argv[1]).resolve(), sys.argv[2]


def fletcher32(data):
    """H5checksum.c's Fletcher-32: 16-bit big-endian words, sums from 0, an odd last byte high."""
    if len(data) % 2:
        data = data + b"\0"
    words = np.frombuffer(data, dtype=">u2").astype(np.uint64)
    sum1 = sum2 = 0
    for start in range(0, len(words), 360):
        block = words[start:start + 360]
        partial = np.cumsum(block) + sum1
        sum2 += int(partial.sum())
        sum1 = int(partial[-1])
        sum1 = (sum1 & 0xFFFF) + (sum1 >> 16)
        sum2 = (sum2 & 0xFFFF) + (sum2 >> 16)
    sum1 = (sum1 & 0xFFFF) + (sum1 >> 16)
    sum2 = (sum2 & 0xFFFF) + (sum2 >> 16)
    return (sum2 << 16) | sum1


def decode(dataset, raw, chunk_shape):
    """The chunk's values from its stored bytes: checksum, inflate, unshuffle (the filters' reverse
    order: h5py lists them in pipeline order, shuffle first)."""
    assert dataset.fletcher32
    body, stored = raw[:-4], int.from_bytes(raw[-4:], "little")
    assert fletcher32(body) == stored, f"{dataset.name}: Fletcher-32 mismatch"
    data = zlib.decompress(body) if dataset.compression == "gzip" else body
    size = dataset.dtype.itemsize
    if dataset.shuffle and size > 1:
        count = len(data) // size
        data = np.frombuffer(data[:count * size], np.uint8).reshape(size, count).T.tobytes() + data[count * size:]
    return np.frombuffer(data, dtype=dataset.dtype).reshape(chunk_shape)


with tempfile.TemporaryDirectory() as directory:
    study = pathlib.Path(directory) / "s.toml"
    study.write_text(f"""format_version = 1
name = "worker_chunks"
aircraft = "{root / 'studies' / 'aircraft' / 'ance.toml'}"
[analyses.modes]
[analyses.open_loop]
duration_s = 2.0
step_s = 0.01
[output]
chunk_runs = 32
time_series = true
output_dt_s = 0.1
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [28.0, 40.0, 7]
[[design.parameter]]
name = "height_m"
linspace = [0.8, 6.0, 23]
""")
    archive = pathlib.Path(directory) / "a.h5"
    subprocess.run([binary, "run", str(study), "-o", str(archive), "-q", "--threads", "2"], check=True)

    chunks_checked = 0
    with h5py.File(archive, "r") as f:
        runs = f["runs/status"].shape[0]
        assert runs == 161
        per_run = []
        # (not the root's netCDF dimensions, schemas/archive.md: no stored values)
        f.visititems(lambda name, obj: per_run.append(name) if isinstance(obj, h5py.Dataset)
                     and obj.shape[:1] == (runs,) and "/" in name else None)
        assert len(per_run) > 30, per_run
        for name in per_run:
            dataset = f[name]
            assert dataset.compression == "gzip" and dataset.compression_opts == 1, (name, dataset.compression)
            assert dataset.fletcher32, name
            assert dataset.shuffle == (dataset.dtype.itemsize > 1 and dataset.dtype.kind != "S"), name
            values = dataset[()]
            rows = dataset.chunks[0]
            for first in range(0, runs, rows):
                offset = (first,) + (0,) * (dataset.ndim - 1)
                if dataset.id.get_chunk_info_by_coord(offset).byte_offset is None:
                    assert name == "runs/message", f"{name}: chunk at {first} not written"
                    continue
                mask, raw = dataset.id.read_direct_chunk(offset)
                assert mask == 0, (name, first, mask)
                chunk = decode(dataset, raw, dataset.chunks)
                present = min(rows, runs - first)
                assert chunk[:present].tobytes() == values[first:first + present].tobytes(), (name, first)
                chunks_checked += 1

        # The engine's own values for a few runs, computed in another process: bit for bit.
        speeds = f["design/speed_mps"][()]
        heights = f["design/height_m"][()]
        sigma = f["results/modes/stability_margin_per_s"][()]
        eigenvalues = f["results/modes/eigenvalues"][()]
        for run in (0, 31, 32, 100, 160):  # first and last run of a batch, the partial last batch
            out = subprocess.run([binary, "modes", "--aircraft", str(root / "studies" / "aircraft" / "ance.toml"),
                                  "--speed-mps", repr(float(speeds[run])), "--heights-m", repr(float(heights[run])),
                                  "--format", "json"], check=True, capture_output=True, text=True).stdout
            row = json.loads(out)["rows"][0]
            direct = sorted((re, im) for re, im in row["eigenvalues"])
            stored = sorted((float(z["re"]), float(z["im"])) for z in eigenvalues[run])
            assert direct == stored, (run, direct, stored)
            assert max(re for re, _ in direct) == max(re for re, _ in stored)
            assert np.isfinite(sigma[run])

    # The stock tool reads it too.
    dump = subprocess.run(["h5dump", "-d", "results/modes/stability_margin_per_s", "-p", str(archive)],
                          check=True, capture_output=True, text=True).stdout
    assert "COMPRESSION DEFLATE { LEVEL 1 }" in dump and "CHECKSUM FLETCHER32" in dump and "PREPROCESSING SHUFFLE" in dump
print(f"worker-compressed chunks: {chunks_checked} chunks decoded independently, equal to HDF5's reading and to "
      "the engine's direct values")
