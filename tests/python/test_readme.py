"""README's "From Python" block runs as written (paths moved to a temporary directory), and says
what it claims: H* at the paper's speed, a 160 x 600 map, the archive's grid dimensions."""
import math
import os
import re

from conftest import ROOT


def test_readme_from_python_block_runs(gesweep, tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## From Python"):]
    block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    block = block.replace("results/stability_map.h5", str(tmp_path / "stability_map.h5"))
    import matplotlib
    matplotlib.use("Agg")
    monkeypatch.chdir(ROOT)
    scope = {}
    exec(compile(block, "README.md (From Python)", "exec"), scope)
    assert scope["m"]["stability_margin_per_s"].shape == (160, 600)
    assert math.isfinite(scope["b"]["height_m"]) and scope["b"]["crossings"]
    assert scope["ds"].stability_margin_per_s.dims == ("speed_mps", "height_m")
    scope["ds"].close()
