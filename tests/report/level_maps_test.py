#!/usr/bin/python3
"""The report's level maps come from the column manifest (issue 15): an analysis the report has never
heard of, whose int8 columns have the levels "level 1", ... (role "rating" in the manifest), is drawn
as a level map over height x speed with its parts' lines and its own section, with no edit of
scripts/report. The new analysis here ("ride_quality", three parts and no overall rating) is made by
moving the flying_qualities columns of a real sweep to new names in a copy of the archive, and adding
its entry to the engine's manifest (`gesweep columns --json`) in a file that GESWEEP_COLUMNS_MANIFEST
names. The oracle is h5py on the archive: with no overall column the map is the worst (largest code)
of the parts at each cell.
Run by ctest (tests/report/CMakeLists.txt) with the gesweep binary as the first argument.
"""
import copy
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import h5py
import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.collections import QuadMesh  # noqa: E402

GESWEEP = os.path.abspath(sys.argv.pop(1))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
WORK = tempfile.mkdtemp(prefix="gesweep_level_maps_test_")
MANIFEST = os.path.join(WORK, "columns.json")
os.environ["GESWEEP_COLUMNS_MANIFEST"] = MANIFEST  # read by scripts/lib/columns.py at import
PAPER_SPEED_MPS = 32.0208
# The new analysis: part name -> the flying_qualities column it is made of (roll: the phugoid one
# level worse, capped at the worst, so that the worst of the parts differs from each part).
NEW = "ride_quality"
PARTS = {"vertical_level": "phugoid_level", "pitch_level": "short_period_level", "roll_level": "phugoid_level"}

sys.path.insert(0, os.path.join(ROOT, "scripts", "report"))


def setUpModule():
    global FLYING, RIDE, report_data, figures_common, figures_levels
    FLYING = os.path.join(WORK, "flying_qualities.h5")
    out = subprocess.run([GESWEEP, "run", "tests/report/flying_qualities_small.toml", "-o", FLYING, "-q"],
                         capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    RIDE = os.path.join(WORK, "ride.h5")
    shutil.copy(FLYING, RIDE)
    with h5py.File(RIDE, "r+") as f:
        f.attrs["study_name"] = "test_ride_quality"
        source = f["results/flying_qualities"]
        target = f.create_group(f"results/{NEW}")
        for part, column in PARTS.items():
            values = source[column][...]
            if part == "roll_level":
                values = np.minimum(values + 1, 3).astype(values.dtype)
            d = target.create_dataset(part, data=values)
            for key, value in source[column].attrs.items():
                d.attrs[key] = value
            d.attrs["description"] = f"Example standard level of the {part.removesuffix('_level')} (1.2.3)"
        del f["results/flying_qualities"]
    out = subprocess.run([GESWEEP, "columns", "--json"], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr
    manifest = json.loads(out.stdout)
    template = next(c for a in manifest["analyses"] if a["name"] == "flying_qualities" for c in a["columns"]
                    if c["name"] == "phugoid_level")
    new_columns = []
    for part in PARTS:
        c = copy.deepcopy(template)
        c.update(path=f"results/{NEW}/{part}", name=part, role="rating",
                 description=f"Example standard level of the {part.removesuffix('_level')} (1.2.3)")
        new_columns.append(c)
    manifest["analyses"].append({"name": NEW, "description": "an example rating of three parts",
                                 "needs_model": True, "parameters_used": ["height_m", "speed_mps"],
                                 "columns": new_columns, "time_axes": []})
    with open(MANIFEST, "w", encoding="utf-8") as f:
        json.dump(manifest, f)
    import report_data as data  # noqa: E402  (after GESWEEP_COLUMNS_MANIFEST is set)
    import figures_common as common  # noqa: E402
    import figures_levels as levels  # noqa: E402
    report_data, figures_common, figures_levels = data, common, levels


def tearDownModule():
    shutil.rmtree(WORK, ignore_errors=True)


def draw_levels(paths):
    """figures_levels.draw on archives: (Figure records, {file: (mesh values, legend texts)})."""
    seen = {}

    def observe(fig, name):
        ax = fig.axes[0]
        mesh = next(c for c in ax.collections if isinstance(c, QuadMesh))
        legend = [t.get_text() for a in fig.axes if a.get_legend() for t in a.get_legend().get_texts()]
        seen[name] = (np.ma.filled(mesh.get_array().astype(float), np.nan), legend, ax.get_title())
    archives = report_data.open_archives(paths)
    figures_common.observers.append(observe)
    try:
        figures = figures_levels.draw(archives, tempfile.mkdtemp(dir=WORK))
    finally:
        figures_common.observers.remove(observe)
        for archive in archives:
            archive.close()
    return figures, seen


class LevelMaps(unittest.TestCase):
    def test_a_new_rated_analysis_is_drawn_from_the_manifest(self):
        figures, seen = draw_levels([FLYING, RIDE])
        files = sorted(f.file for f in figures)
        self.assertEqual(len(files), 2, files)
        self.assertTrue(files[0].startswith("flying_qualities_test_flying_qualities"), files)
        self.assertTrue(files[1].startswith(f"{NEW}_test_ride_quality"), files)
        ride = next(f for f in figures if f.file.startswith(NEW))
        values, legend, title = seen[ride.file]
        # The oracle: h5py on the archive, on the same speed x height grid.
        with h5py.File(RIDE, "r") as f:
            speed, height = f["design/speed_mps"][...], f["design/height_m"][...]
            parts = {p: f[f"results/{NEW}/{p}"][...].astype(float) for p in PARTS}
            names = [v.decode() if isinstance(v, bytes) else v for v in f[f"results/{NEW}/vertical_level"].attrs["levels"]]
        speeds, heights = np.unique(speed), np.unique(height)
        worst = np.full((len(heights), len(speeds)), np.nan)
        worst[np.searchsorted(heights, height), np.searchsorted(speeds, speed)] = np.max(np.stack(list(parts.values())),
                                                                                          axis=0)
        np.testing.assert_array_equal(values.reshape(worst.shape), worst)
        # Not one part's map under another name: the worst differs from the vertical and the pitch parts.
        for p in ("vertical_level", "pitch_level"):
            self.assertFalse(np.array_equal(parts[p], np.max(np.stack(list(parts.values())), axis=0)), p)
        self.assertEqual(title, "the level: the worst of vertical (1.2.3), pitch (1.2.3), roll (1.2.3)")
        # A line for each part that changes level on the grid, named by the part.
        for p, codes in parts.items():
            label = f"{p.removesuffix('_level')}: where it loses a level (between the colours)"
            self.assertEqual(label in legend, bool(np.nanmin(codes) < np.nanmax(codes)), (label, legend))
        # The caption says where each part loses each level at the paper's speed, as h5py reads it.
        at = speed == PAPER_SPEED_MPS
        order = np.argsort(height[at])[::-1]
        for p, codes in parts.items():
            code, h = codes[at][order], height[at][order]
            self.assertIn(f"At u0 = {PAPER_SPEED_MPS:g} m/s the {p.removesuffix('_level')} is", ride.caption)
            for i in range(1, len(code)):
                if code[i] != code[i - 1]:
                    self.assertIn(f"{names[int(code[i])]} from {h[i]:.4g} m", ride.caption)
        self.assertIn("an example rating of three parts", ride.caption)

    def test_the_page_has_a_section_for_the_new_analysis(self):
        out_dir = os.path.join(WORK, "page")
        env = dict(os.environ, GESWEEP_COLUMNS_MANIFEST=MANIFEST)
        run = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "scripts", "report", "report.py"), "-o", out_dir,
                              "--quiet", "--", FLYING, RIDE], capture_output=True, text=True, env=env, timeout=600)
        self.assertEqual(run.returncode, 0, run.stderr)
        with open(os.path.join(out_dir, "index.html"), encoding="utf-8") as f:
            page = f.read()
        self.assertIn(f'<h2 id="{NEW}">Ride quality (levels)</h2>', page)
        self.assertIn('<h2 id="flying_qualities">Flying qualities (MIL-F-8785C, Category C)</h2>', page)
        self.assertLess(page.index('id="flying_qualities"'), page.index(f'id="{NEW}"'))
        self.assertEqual(len(glob.glob(os.path.join(out_dir, f"{NEW}_*.png"))), 1)


if __name__ == "__main__":
    unittest.main(verbosity=2)
