#!/usr/bin/python3
"""Runs the five-line h5py snippet of schemas/archive.md on a fresh archive written by the real
gesweep binary, and checks what it reads against the archive's own bookkeeping.
Usage: archive_snippet_test.py REPO_ROOT GESWEEP_BINARY"""
import pathlib
import re
import subprocess
import sys
import tempfile

import h5py
import numpy as np

root, binary = pathlib.Path(sys.argv[1]).resolve(), sys.argv[2]
text = (root / "schemas" / "archive.md").read_text()
snippet = re.search(r"```python\n(.*?)```", text, re.S).group(1)
assert len(snippet.strip().splitlines()) == 5, "the archive.md snippet must stay five lines"
readme = (root / "README.md").read_text()
assert snippet in readme, "README's h5py snippet must be archive.md's (tested here)"
# README's study example is studies/map_h_terms.toml (run by validate_studies.py with every study).
example = re.search(r"```toml\n(.*?)```", readme, re.S).group(1)
assert example in (root / "studies" / "map_h_terms.toml").read_text(), \
    "README's study example must be the body of studies/map_h_terms.toml"

with tempfile.TemporaryDirectory() as directory:
    study = pathlib.Path(directory) / "s.toml"
    study.write_text(f"""format_version = 1
aircraft = "{root / 'studies' / 'aircraft' / 'ance.toml'}"
[analyses.modes]
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
values = [30.0, 40.0]
[[design.parameter]]
name = "height_m"
linspace = [1.0, 6.0, 11]
""")
    archive = pathlib.Path(directory) / "a.h5"
    subprocess.run([binary, "run", str(study), "-o", str(archive), "-q"], check=True)
    scope = {}
    exec(snippet.replace("results/stability_map.h5", str(archive)), scope)
    assert scope["sigma"].shape == (22,), scope["sigma"].shape
    assert np.all(np.isfinite(scope["sigma"]))
    f = h5py.File(archive, "r")
    assert f["results/modes/stability_margin_per_s"].attrs["units"] == "1/s"
    assert list(scope["u"][:3]) == [30.0, 30.0, 30.0] and scope["H"][1] == 1.5
    eigenvalues = f["results/modes/eigenvalues"][:]
    assert np.allclose(scope["sigma"], [max(z["re"] for z in row if abs(complex(z["re"], z["im"])) > 1e-9) for row in eigenvalues])
print("schemas/archive.md snippet: ok")
