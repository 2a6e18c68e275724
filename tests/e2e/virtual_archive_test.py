#!/usr/bin/python3
"""A virtual merged archive is read as one archive by every reader (docs/sweep.md, "Sharding and merge").

  virtual_archive_test.py REPO_ROOT GESWEEP_BINARY

A stability map run in one process and as 3 shards merged virtually (the default) and by copy:
  - `gesweep query`, `gesweep boundary --archive` (which also writes /analysis/boundary into the
    merged file) and h5py give the same output for the merged archives as for the single run;
  - `gesweep report` makes its report from the virtual archive;
  - the virtual file is a small fraction of the shards' size; moving a shard away makes every
    reader refuse it with one line naming the shard (exit 2), not read fill values;
  - the merge prints that the shards must stay where they are.
"""
import pathlib
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

root, binary = pathlib.Path(sys.argv[1]).resolve(), sys.argv[2]


def gesweep(*args, code=0):
    result = subprocess.run([binary, *map(str, args)], capture_output=True, text=True)
    assert result.returncode == code, f"gesweep {' '.join(map(str, args))}: exit {result.returncode}\n{result.stderr}"
    return result


with tempfile.TemporaryDirectory() as directory:
    work = pathlib.Path(directory)
    study = work / "map.toml"
    study.write_text(f"""format_version = 1
name = "virtual_map"
aircraft = "{root / 'studies' / 'aircraft' / 'ance.toml'}"
[analyses.modes]
[output]
chunk_runs = 128
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [28.0, 60.0, 9]
[[design.parameter]]
name = "height_m"
logspace = [0.79, 14.0, 200]
""")
    single = work / "single.h5"
    gesweep("run", study, "-o", single, "-q")
    shards = []
    for i in range(3):
        shards.append(work / "shards" / f"shard-{i}.h5")
        shards[-1].parent.mkdir(exist_ok=True)
        gesweep("run", study, "-o", shards[-1], "--shard", f"{i}/3", "-q")
    virtual, copy = work / "virtual.h5", work / "copy.h5"
    merged = gesweep("merge", *shards, "-o", virtual)
    assert "keep them where they are" in merged.stderr, merged.stderr
    gesweep("merge", *shards, "-o", copy, "--copy", "-q")
    shard_bytes = sum(s.stat().st_size for s in shards)
    assert virtual.stat().st_size < shard_bytes / 5, (virtual.stat().st_size, shard_bytes)

    where = ["--where", "speed_mps > 40 and height_m < 3", "--columns", "speed_mps,height_m,stability_margin_per_s"]
    def query(archive):  # the footer names the archive
        return gesweep("query", archive, *where).stdout.replace(str(archive), "ARCHIVE")

    expected_query = query(single)
    expected_boundary = gesweep("boundary", "--archive", single).stdout
    for archive in (virtual, copy):
        assert query(archive) == expected_query, archive
        assert gesweep("boundary", "--archive", archive).stdout.replace(str(archive), "X") == \
            expected_boundary.replace(str(single), "X"), archive
        with h5py.File(single, "r") as a, h5py.File(archive, "r") as b:
            for name in ("results/modes/stability_margin_per_s", "results/modes/eigenvalues", "runs/status",
                         "design/height_m", "analysis/boundary/height_m"):
                assert a[name][()].tobytes() == b[name][()].tobytes(), (archive, name)
            assert b["results/modes/stability_margin_per_s"].is_virtual == (archive == virtual)
    report = work / "report"
    gesweep("report", virtual, "-o", report)
    assert (report / "index.html").exists()

    # A shard moved away: one line naming it, exit 2, from every reader.
    shutil.move(shards[1], work / "elsewhere.h5")
    for command in (["query", virtual, *where], ["boundary", "--archive", virtual]):
        refused = gesweep(*command, code=2)
        lines = [line for line in refused.stderr.splitlines() if line.strip()]
        assert len(lines) == 1 and "shard-1.h5" in lines[0] and "must stay" in lines[0], refused.stderr
    # The copy does not need the shards.
    assert query(copy) == expected_query
print("virtual archive: query, boundary --archive, report and h5py read it as one archive; a moved shard is refused")
