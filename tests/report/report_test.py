#!/usr/bin/python3
"""End-to-end test of `gesweep report` (issues 6 and 19): small archives of the ANCE (a stability grid
with its refined boundary, a short Fig. 4 study, the paper's landing pair, a Morris sensitivity),
rendered into one page; every image the page references exists and is a non-blank PNG; the tables
carry what h5py reads from the same archives; a figure is drawn only when its data exist; the figures'
own fixes (legends clear of the data, labels that do not overlap, the locus' speed named, distinct
open-loop lines) are checked on the figures as drawn; and headless Chromium (Debian's chromium, in
GESWEEP_PACKAGES) loads the page, and a screenshot of it shows every image the page references,
pixel for pixel what the PNG holds.
Run by ctest (tests/report/CMakeLists.txt) with the gesweep binary as the first argument.
"""
import html
import html.parser
import itertools
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.image  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import QuadMesh  # noqa: E402
from matplotlib.text import Annotation, Text  # noqa: E402

GESWEEP = os.path.abspath(sys.argv.pop(1))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
WORK = tempfile.mkdtemp(prefix="gesweep_report_test_")
ARCHIVES = os.path.join(WORK, "archives")
# A rendered figure or screenshot is "not blank" when its pixels vary at least this much (0..1 scale).
MIN_PIXEL_STD = 0.02
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--hide-scrollbars", "--force-device-scale-factor=1"]
# The page is laid out at this window width (CSS pixels) for the screenshot.
SCREEN_WIDTH = 1280
# An image as painted in the screenshot matches its PNG when, both averaged over blocks of
# COMPARE_BLOCKS, the mean absolute difference is below this (0..1 scale): the browser's scaling
# filter and colour handling move block means by well under 0.01, a broken-image icon by far more.
COMPARE_BLOCKS = (24, 36)
MAX_BLOCK_DIFFERENCE = 0.02
# Colours of two open-loop lines are told apart when their RGB distance (0..sqrt 3) is at least
# this; ten viridis samples, the old colours, come within 0.10 of each other.
MIN_LINE_COLOUR_DISTANCE = 0.2
# The short-period derivative that jumps between two rows of the paper's Table A2 (issue 19): the
# rows and values as the paper prints them.
TABLE_A2_JUMP = ("1.2968 m and 1.5561 m", "CMα̇ jumps from -18.71 to -9.307")
PAPER_SPEED_MPS = 32.0208

sys.path.insert(0, os.path.join(ROOT, "scripts", "report"))
import report_data  # noqa: E402
import report_figures  # noqa: E402


def run(*args, timeout=300):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=timeout, cwd=ROOT)


def sweep(study, name):
    path = os.path.join(ARCHIVES, name)
    out = run("run", study, "-o", path, "-q")
    assert out.returncode == 0, out.stderr
    return path


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.images, self.links, self.ids = [], [], []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "img":
            self.images.append(attrs)
        for key in ("src", "href"):
            if key in attrs:
                self.links.append(attrs[key])
        if "id" in attrs:
            self.ids.append(attrs["id"])


def parse(path):
    page = Page()
    with open(path, encoding="utf-8") as f:
        text = f.read()
    page.feed(text)
    return page, text


def modes_study(name, speeds, heights):
    """A modes study over speeds x heights (logspace from 0.7882 m to 14 m) outside ARCHIVES; its archive."""
    os.makedirs(EXTRA, exist_ok=True)
    path = os.path.join(EXTRA, name + ".toml")
    with open(path, "w") as f:
        f.write(f'format_version = 1\nname = "{name}"\naircraft = "{os.path.join(ROOT, "studies/aircraft/ance.toml")}"\n'
                f'[analyses.modes]\n[design]\nkind = "grid"\n[[design.parameter]]\nname = "speed_mps"\n'
                f'values = {list(speeds)}\n[[design.parameter]]\nname = "height_m"\nlogspace = [0.7882, 14.0, {heights}]\n')
    archive = os.path.join(EXTRA, name + ".h5")
    out = run("run", path, "-o", archive, "-q")
    assert out.returncode == 0, out.stderr
    return archive


def setUpModule():
    os.makedirs(ARCHIVES)
    global GRID, OPEN_LOOP, LANDING, MORRIS, FLYING
    GRID = sweep("tests/query/boundary_grid.toml", "grid.h5")
    FLYING = sweep("tests/report/flying_qualities_small.toml", "flying_qualities.h5")
    out = run("boundary", "--archive", GRID)
    assert out.returncode == 0, out.stderr
    OPEN_LOOP = sweep("tests/report/open_loop_small.toml", "open_loop.h5")
    LANDING = sweep("studies/paper/landing.toml", "landing.h5")
    MORRIS = sweep("studies/verification/morris_linear.toml", "morris.h5")
    run("sensitivity", MORRIS, "--output", "linear")  # a colleague's command; its absence only drops a figure


EXTRA = os.path.join(WORK, "extra")


def describe(fig):
    """What the tests check of a drawn figure, in display coordinates of its final layout."""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    out = {"maps": [], "axes": [], "legends": [], "labels": [], "lines": []}
    for ax in fig.axes:
        box = ax.get_window_extent(renderer)
        out["axes"].append((ax.get_title(), box))
        if ax.get_label() != "<colorbar>" and any(isinstance(c, QuadMesh) for c in ax.collections):
            out["maps"].append(box)
        legend = ax.get_legend()
        if legend is not None:
            out["legends"].append(([t.get_text() for t in legend.get_texts()], legend.get_window_extent(renderer)))
        for text in ax.texts:
            if isinstance(text, Annotation):
                text.update_positions(renderer)
                out["labels"].append((ax.get_title(), text.get_text(), Text.get_window_extent(text, renderer), box))
        out["lines"] += [(ax.get_title(), line.get_label(), line.get_color(), line.get_linestyle())
                         for line in ax.get_lines()]
    return out


def draw(function, paths):
    """Runs a figure function of scripts/report on archives; (Figure records, descriptions by file)."""
    described = {}
    original = report_figures._save

    def save(fig, outdir, name):
        described[name] = describe(fig)
        return original(fig, outdir, name)
    archives = report_data.open_archives(paths)
    out_dir = tempfile.mkdtemp(prefix="figures_", dir=WORK)
    report_figures._save = save
    try:
        figures = function(archives, out_dir)
    finally:
        report_figures._save = original
        for archive in archives:
            archive.close()
    return figures, described


class Figures(unittest.TestCase):
    """The figure fixes of issue 19, checked on the figures as drawn."""

    def test_stability_map_legend_clear_of_the_maps_and_the_phugoid_panel(self):
        figures, described = draw(report_figures.stability_maps, [GRID])
        self.assertEqual(len(figures), 2)  # one per h_derivatives value
        for figure in figures:
            d = described[figure.file]
            self.assertEqual(len(d["maps"]), 2, "σ and the phugoid's own margin")
            self.assertIn("phugoid", " ".join(title for title, _ in d["axes"]))
            self.assertEqual(len(d["legends"]), 1)
            texts, legend = d["legends"][0]
            for box in d["maps"]:
                self.assertFalse(legend.overlaps(box), f"the legend covers a map: {texts}")
            self.assertTrue(any(t.startswith("last table row (13.373 m)") for t in texts), texts)
        # With the h-derivatives the band above the last table row is explained, with values from the
        # archive; without them the height root is neutral at every height, σ is never it, and there is
        # no band to explain.
        self.assertIn("Above the last table row (13.373 m)", figures[1].caption)
        self.assertIn("the height root is exactly neutral", figures[1].caption)
        self.assertNotIn("Above the last table row", figures[0].caption)
        with h5py.File(GRID, "r") as f:
            height, sigma = f["design/height_m"][...], f["results/modes/stability_margin_per_s"][...]
            on = f["design/h_derivatives"][...] == 1
        just_below = np.max(height[height < 13.373])
        median = float(np.median(sigma[on & (height == just_below)]))
        self.assertIn(f"median {median:.2g} 1/s at {just_below:.4g} m", figures[1].caption)

    def test_root_locus_at_the_paper_speed_names_it_and_explains_the_straight_stretch(self):
        near = modes_study("near_paper_speed", [31.9], 120)
        paper = modes_study("at_paper_speed", [PAPER_SPEED_MPS], 60)
        # The denser group at 31.9 m/s used to win; the paper's own speed does now.
        figures, described = draw(report_figures.root_locus, [near, paper])
        self.assertEqual(len(figures), 1)
        self.assertIn(f"at u0 = {PAPER_SPEED_MPS:g} m/s (the paper's speed)", figures[0].caption)
        self.assertIn("at_paper_speed.h5", figures[0].caption)
        self.assertIn("between the table rows at " + TABLE_A2_JUMP[0] + ", where " + TABLE_A2_JUMP[1],
                      figures[0].caption)
        labels = described["root_locus.png"]["labels"]
        self.assertGreaterEqual(len(labels), 9)  # four heights in each of two panels, and the stretch
        for (_, a, box_a, _), (_, b, box_b, _) in itertools.combinations(labels, 2):
            self.assertFalse(box_a.overlaps(box_b), f"labels {a!r} and {b!r} overlap")
        for title, text, box, frame in labels:
            self.assertTrue(frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1,
                            f"label {text!r} leaves the panel {title!r}")

    def test_root_locus_off_the_paper_speed_says_which_speed(self):
        near = modes_study("off_paper_speed", [31.5, 33.0], 60)
        figures, _ = draw(report_figures.root_locus, [near])
        self.assertIn("at u0 = 31.5 m/s, the nearest of its speeds to the paper's 32.0208 m/s", figures[0].caption)

    def test_flying_qualities_say_where_each_level_is_lost(self):
        figures, described = draw(report_figures.level_maps, [FLYING])
        self.assertEqual(len(figures), 1)
        self.assertEqual(len(described[figures[0].file]["maps"]), 1)
        # The caption's heights are the archive's: from the top down at the paper's speed, the first
        # height of each new level of the phugoid (codes: level n is n - 1), as h5py reads them.
        with h5py.File(FLYING, "r") as f:
            at = f["design/speed_mps"][...] == PAPER_SPEED_MPS
            height = f["design/height_m"][...][at]
            code = f["results/flying_qualities/phugoid_level"][...][at]
            names = [v.decode() if isinstance(v, bytes) else v
                     for v in f["results/flying_qualities/phugoid_level"].attrs["levels"]]
        order = np.argsort(height)[::-1]
        height, code = height[order], code[order]
        changes = [i for i in range(1, len(code)) if code[i] != code[i - 1]]
        self.assertGreaterEqual(len(changes), 2)  # level 2 -> level 3 -> worse, docs/model.md section 11
        for i in changes:
            self.assertIn(f"{names[code[i]]} from {height[i]:.4g} m", figures[0].caption)
        self.assertIn(f"At u0 = {PAPER_SPEED_MPS:g} m/s the phugoid is", figures[0].caption)

    def test_open_loop_lines_are_told_apart(self):
        styles = report_figures._distinct_styles(report_figures.MAX_OPEN_LOOP_LINES)
        for (a, style_a), (b, style_b) in itertools.combinations(styles, 2):
            if style_a == style_b:
                self.assertGreaterEqual(float(np.linalg.norm(np.subtract(a[:3], b[:3]))), MIN_LINE_COLOUR_DISTANCE)
        figures, described = draw(report_figures.open_loop, [OPEN_LOOP])
        lines = [(colour, style) for title, label, colour, style in described[figures[0].file]["lines"]
                 if title == "whole run" and label.startswith("H0 =")]
        self.assertEqual(len(lines), 4)
        self.assertEqual(len(set((str(c), s) for c, s in lines)), 4)

    def test_landing_legend_names_the_wheel_contact_line(self):
        figures, described = draw(report_figures.landing, [LANDING])
        texts = [t for legend, _ in described[figures[0].file]["legends"] for t in legend]
        self.assertIn("wheel contact (0.788 m)", texts)



def tearDownModule():
    shutil.rmtree(WORK, ignore_errors=True)


class Report(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.out_dir = os.path.join(WORK, "report")
        # A directory of archives and one archive named twice: each is reported once.
        cls.result = run("report", ARCHIVES, GRID, "-o", cls.out_dir)
        cls.index = os.path.join(cls.out_dir, "index.html")

    def test_page_and_every_image_it_references(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        page, text = parse(self.index)
        self.assertGreaterEqual(len(page.images), 4)
        for image in page.images:
            src = image["src"]
            self.assertTrue(image.get("alt"), src)
            self.assertNotIn("/", src, "figures sit beside index.html")
            path = os.path.join(self.out_dir, src)
            self.assertTrue(os.path.isfile(path), src)
            self.assertGreater(os.path.getsize(path), 0, src)
            with open(path, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n", src)
            pixels = matplotlib.image.imread(path)
            self.assertGreater(pixels.shape[0], 200, src)
            self.assertGreater(pixels.shape[1], 200, src)
            self.assertGreater(float(np.std(pixels[..., :3])), MIN_PIXEL_STD, f"{src} is blank")
        # Self-contained: nothing fetched from elsewhere; links are the page's own anchors.
        for link in page.links:
            self.assertFalse(link.startswith(("http:", "https:", "//")), link)
            if link.startswith("#"):
                self.assertIn(link[1:], page.ids)
        names = [i["src"] for i in page.images]
        for prefix in ("stability_map_", "flying_qualities_", "root_locus", "open_loop_", "landing_"):
            self.assertTrue(any(n.startswith(prefix) for n in names), f"no {prefix} figure in {names}")
        sensitivity_written = False
        with h5py.File(MORRIS, "r") as f:
            sensitivity_written = "analysis/sensitivity" in f
        self.assertEqual(any(n.startswith("sensitivity_") for n in names), sensitivity_written)
        self.assertEqual(text.count("<h3>test_boundary_grid"), 1, "an archive named twice is reported once")

    def test_tables_carry_the_archives_values(self):
        _, text = parse(self.index)
        with h5py.File(GRID, "r") as f:
            group = f["analysis/boundary"]
            heights = group["height_m"][...]
            ratios = group["height_over_span"][...]
        found = np.isfinite(heights)
        self.assertGreater(int(found.sum()), 0)
        for h, r in zip(heights[found], ratios[found]):
            self.assertIn(f"<td class=\"num\">{h:.7g}</td>", text)
            self.assertIn(f"<td class=\"num\">{r:.4g}</td>", text)
        for path in (GRID, OPEN_LOOP, LANDING, MORRIS):
            with h5py.File(path, "r") as f:
                status = f["runs/status"][...]
                name = f.attrs["study_name"]
            ok, failed, pending = (int(np.count_nonzero(status == s)) for s in (1, 2, 0))
            row = (f"<td>{os.path.basename(path)}</td><td>{name}</td><td class=\"num\">{len(status)}</td>"
                   f"<td class=\"num\">{ok}</td><td class=\"num\">{failed}</td><td class=\"num\">{pending}</td>")
            self.assertIn(row, text)
        # The paper's claims: the engine's side is the archives' (landing outcomes as h5py reads them).
        self.assertIn('id="claims"', text)
        with h5py.File(LANDING, "r") as f:
            levels = [v.decode() if isinstance(v, bytes) else v for v in f["results/landing/outcome"].attrs["levels"]]
            outcomes = [levels[int(v)] for v in f["results/landing/outcome"][...]]
            touchdown = f["results/landing/touchdown_time_s"][...]
        for outcome, t in zip(outcomes, touchdown):
            self.assertIn(outcome + (f" at {t:.5g} s" if outcome == "landed" else ""), text)
        with h5py.File(OPEN_LOOP, "r") as f:
            dip = f["results/open_loop/min_height_m"][list(f["design/height_m"][...]).index(2.9987)]
        self.assertIn(f"lowest height {dip:.4g} m", text)
        self.assertIn("Provenance", text)
        with h5py.File(GRID, "r") as f:
            self.assertIn(str(f.attrs["git_commit"]), text)

    def test_boundary_table_is_not_behind_a_click(self):
        _, text = parse(self.index)
        section = text[text.index('id="boundary"'):]
        section = section[:section.index("<h2")]
        self.assertNotIn("<details", section)
        self.assertIn("<table>", section)

    def test_a_figure_only_when_its_data_exist(self):
        out_dir = os.path.join(WORK, "landing_only")
        result = run("report", LANDING, "-o", out_dir, "-q")
        self.assertEqual(result.returncode, 0, result.stderr)
        page, text = parse(os.path.join(out_dir, "index.html"))
        self.assertEqual([i["src"].split("_")[0] for i in page.images], ["landing"])
        self.assertNotIn('id="map"', text)
        self.assertNotIn('id="boundary"', text)
        self.assertEqual(sorted(f for f in os.listdir(out_dir) if f.endswith(".png")),
                         [i["src"] for i in page.images])

    def test_bad_input(self):
        cases = [
            ([os.path.join(WORK, "missing.h5"), "-o", os.path.join(WORK, "r1")], "no such archive"),
            ([os.path.join(ROOT, "tests/report/open_loop_small.toml"), "-o", os.path.join(WORK, "r2")],
             "not an HDF5 file"),
            ([LANDING, "-o", LANDING], "is the input archive"),
            ([LANDING, "-o", os.path.join(ROOT, "tests/report/open_loop_small.toml")],
             "is a regular file; expected a directory"),
            ([LANDING, "-o", os.path.join(WORK, "no", "such", "dir")], "does not exist"),
        ]
        for args, says in cases:
            with self.subTest(args=args):
                result = run("report", *args)
                self.assertEqual(result.returncode, 2, result.stdout + result.stderr)
                self.assertIn(says, result.stderr)
                self.assertEqual(len(result.stderr.strip().splitlines()), 1, result.stderr)

    def test_chromium_loads_and_paints_every_image(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        browser = shutil.which("chromium")
        self.assertIsNotNone(browser, "Debian's chromium is not installed (it is in GESWEEP_PACKAGES of "
                                      "scripts/lib/setup.sh: ./scripts/test installs it)")
        # The page as the report wrote it, plus a script that lists where each image was laid out and
        # whether it loaded (the page itself has no script); it sits beside index.html, so the images
        # resolve the same way.
        page, text = parse(self.index)
        probe = os.path.join(self.out_dir, "probe.html")
        with open(probe, "w", encoding="utf-8") as f:
            f.write(text.replace("</body>", PROBE_SCRIPT + "</body>"))
        dom = chromium(browser, probe, "--dump-dom", "--virtual-time-budget=10000", f"--window-size={SCREEN_WIDTH},1000")
        layout = json.loads(html.unescape(re.search(r'<pre id="probe"[^>]*>(.*?)</pre>', dom, re.S).group(1)))
        self.assertEqual([i["src"] for i in layout["images"]], [i["src"] for i in page.images])
        shot = os.path.join(WORK, "screenshot.png")
        height = int(math.ceil(layout["height"]))
        chromium(browser, probe, f"--screenshot={shot}", f"--window-size={SCREEN_WIDTH},{height}")
        pixels = matplotlib.image.imread(shot)[..., :3]
        self.assertEqual(pixels.shape[:2], (height, SCREEN_WIDTH))
        self.assertGreater(float(np.std(pixels)), MIN_PIXEL_STD, "the screenshot is blank")
        for image in layout["images"]:
            with self.subTest(image=image["src"]):
                self.assertTrue(image["complete"] and image["natural"][0] > 0, f"{image['src']} did not load")
                png = matplotlib.image.imread(os.path.join(self.out_dir, image["src"]))[..., :3]
                self.assertEqual(tuple(image["natural"]), (png.shape[1], png.shape[0]))
                x, y, w, h = (int(round(v)) for v in image["box"])
                self.assertGreater(w, 200)
                painted = pixels[y:y + h, x:x + w]
                self.assertEqual(painted.shape[:2], (h, w), "the image lies outside the screenshot")
                difference = float(np.mean(np.abs(blocks(painted) - blocks(png))))
                self.assertLess(difference, MAX_BLOCK_DIFFERENCE, f"{image['src']} is not what the page shows")


PROBE_SCRIPT = """<script>
window.addEventListener("load", function () {
  var out = {height: document.documentElement.scrollHeight, images: []};
  document.querySelectorAll("img").forEach(function (img) {
    var r = img.getBoundingClientRect();
    out.images.push({src: img.getAttribute("src"), complete: img.complete,
                     natural: [img.naturalWidth, img.naturalHeight],
                     box: [r.left + window.scrollX + img.clientLeft, r.top + window.scrollY + img.clientTop,
                           img.clientWidth, img.clientHeight]});
  });
  var pre = document.createElement("pre");
  pre.id = "probe"; pre.style.display = "none"; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def chromium(browser, page, *flags):
    """Runs headless Chromium on a page with a fresh profile; its stdout."""
    profile = tempfile.mkdtemp(prefix="gesweep_chromium_", dir=WORK)
    result = subprocess.run([browser, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *flags, "file://" + page],
                            capture_output=True, text=True, timeout=180)
    shutil.rmtree(profile, ignore_errors=True)
    return result.stdout


def blocks(pixels):
    """Means of the image over COMPARE_BLOCKS (rows, columns) equal blocks."""
    rows, cols = COMPARE_BLOCKS
    y = np.linspace(0, pixels.shape[0], rows + 1).astype(int)
    x = np.linspace(0, pixels.shape[1], cols + 1).astype(int)
    return np.array([[pixels[y[i]:y[i + 1], x[j]:x[j + 1]].mean(axis=(0, 1)) for j in range(cols)]
                     for i in range(rows)])


if __name__ == "__main__":
    unittest.main(verbosity=2)
