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
# The page is laid out at this window width (CSS pixels) for the screenshot (issue 30: legible at 1400).
SCREEN_WIDTH = 1400
# No cell of the claims table is taller than a screen: this many CSS pixels (a laptop's window).
SCREEN_HEIGHT = 900
# No cell of the claims table holds more text than this (characters; issue 30: a few lines, the
# per-run evidence collapsed).
MAX_CLAIM_CELL_CHARS = 2000
# No legend, tick label or colour-bar label shows a number with more significant digits than this
# (issue 30: "W20 = 30 kt headwind", never "-15.433333").
MAX_LABEL_DIGITS = 4
# The dispersion panels are in a grid of at most this many columns, each at least this wide (pixels of
# the PNG, which the page shows at its size): five panels in one row were 200 px each.
MAX_DISPERSION_COLUMNS = 3
MIN_DISPERSION_PANEL_PX = 280
# The page's column at a 1400 px window (report.py's CSS: 1200 px less its padding): a figure no wider
# is shown at its own size, not scaled down.
PAGE_COLUMN_PX = 1168
# A legend lies inside its figure when within this many pixels of its edges (antialiasing).
LEGEND_SLACK_PX = 1.0
# 1 kt in m/s, from its definition (1852 m per hour): the oracle of the wind labels.
KNOT_MPS = 1852.0 / 3600.0
# A number in a label: an optional sign (ASCII or Unicode minus), digits with an optional fraction and
# exponent, not part of a word or of a longer dotted number.
NUMBER = re.compile(r"(?<![\w.])[-−+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?")
# README's sections and the report's: each README section that shows a result names the report
# sections (ids) that show it; the others say why the report has none. A new README section must be
# added to one of the two (issue 30: the demo's report shows every section README shows).
README_IN_REPORT = {
    "Modes and the stability boundary": ("locus", "boundary", "claims"),
    "Flying qualities (MIL-F-8785C, Category C)": ("flying_qualities",),
    "Sweeps, archives, queries and reports": ("map", "boundary", "status", "provenance"),
    "Sobol sensitivity of the boundary": ("sensitivity",),
    "Open-loop time responses (the paper's Fig. 4)": ("open_loop", "claims"),
    "Automatic landing": ("landing", "claims"),
    "Landing dispersion in wind and turbulence": ("dispersion",),
}
README_NOT_IN_REPORT = {
    "Two commands": "how to build and run, no result",
    "The model in one paragraph": "the model, no result",
    "From Python": "the module and the notebook (notebooks/), no archive product",
    "Running on a cluster": "how to run on Slurm, no result",
    "Which coefficient moves the boundary? Local sensitivities": "printed by gesweep boundary --sensitivities, "
                                                                  "not stored in an archive",
    "Performance": "scripts/bench's measurements, not an archive",
    "Aircraft files": "the input format",
    "Layout": "the repository's folders",
    "Landing risk at 10⁻⁶: subset simulation": "a 4.5-min study the demo does not run; `gesweep report` of its "
                                                 "archive draws it in the dispersion section (tests/risk)",
}
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
import figures_common  # noqa: E402
import figures_dispersion  # noqa: E402
import figures_landing  # noqa: E402
import figures_levels  # noqa: E402
import figures_maps  # noqa: E402
import figures_modes  # noqa: E402
import figures_open_loop  # noqa: E402
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


def page_sections(text):
    """{id: html} of each <h2 id=...> section of a report page."""
    parts = re.split(r'<h2 id="([^"]+)">', text)
    return {parts[i]: parts[i + 1] for i in range(1, len(parts) - 1, 2)}


def claim_rows(text):
    """The claims table's rows, each a list of its cells' text (tags dropped, the collapsed evidence
    included)."""
    table = re.search(r'<table class="claims">(.*?)</table>', text, re.S).group(1)
    rows = []
    for row in re.findall(r"<tr>(.*?)</tr>", table, re.S)[1:]:
        rows.append([html.unescape(re.sub(r"<[^>]+>", " ", cell)) for cell in re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)])
    return rows


def claim_cells(text):
    return [cell for row in claim_rows(text) for cell in row]


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
    global GRID, OPEN_LOOP, LANDING, MORRIS, FLYING, DISPERSION
    GRID = sweep("tests/query/boundary_grid.toml", "grid.h5")
    FLYING = sweep("tests/report/flying_qualities_small.toml", "flying_qualities.h5")
    out = run("boundary", "--archive", GRID)
    assert out.returncode == 0, out.stderr
    OPEN_LOOP = sweep("tests/report/open_loop_small.toml", "open_loop.h5")
    LANDING = sweep("studies/paper/landing.toml", "landing.h5")
    MORRIS = sweep("studies/verification/morris_linear.toml", "morris.h5")
    run("sensitivity", MORRIS, "--output", "linear")  # a colleague's command; its absence only drops a figure
    DISPERSION = sweep("tests/report/dispersion_small.toml", "dispersion.h5")
    out = run("dispersion", DISPERSION, "--group-by", "wind_20ft_mps", "--limit", "touchdown_sink_rate_mps>1.83",
              "--limit", "touchdown_distance_past_transmitter_m>518", "--limit", "touchdown_pitch_deg<0")
    assert out.returncode == 0, out.stderr


EXTRA = os.path.join(WORK, "extra")


def describe(fig):
    """What the tests check of a drawn figure, in display coordinates of its final layout."""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    out = {"maps": [], "axes": [], "legends": [], "labels": [], "lines": [], "texts": label_texts(fig),
           "size": tuple(fig.get_size_inches() * fig.dpi), "figure_box": fig.bbox.frozen()}
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


def label_texts(fig):
    """Every legend text, tick label and axis label of a drawn figure's axes (colour bars and secondary
    axes included), as (where, text)."""
    out = []
    axes = list(fig.axes)
    axes += [child for ax in fig.axes for child in ax.child_axes]
    for ax in axes:
        for axis_name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            out += [(f"{axis_name} tick", t.get_text()) for t in axis.get_ticklabels() if t.get_visible()]
            out.append((f"{axis_name} label", axis.get_label().get_text()))
        legend = ax.get_legend()
        if legend is not None:
            out += [("legend", t.get_text()) for t in legend.get_texts()]
    return [(where, text) for where, text in out if text]


def significant_digits(token):
    """The significant digits a number's text shows: "2.5935" 5, "0.0125" 3, "2000" 1, "1.50" 3."""
    mantissa = re.split("[eE]", token.lstrip("-−+"))[0]
    digits = mantissa.replace(".", "").lstrip("0")
    return len(digits if "." in mantissa else digits.rstrip("0"))


def draw(function, paths):
    """Runs a figure function of scripts/report on archives; (Figure records, descriptions by file)."""
    described = {}

    def observe(fig, name):
        described[name] = describe(fig)
    archives = report_data.open_archives(paths)
    out_dir = tempfile.mkdtemp(prefix="figures_", dir=WORK)
    figures_common.observers.append(observe)
    try:
        figures = function(archives, out_dir)
    finally:
        figures_common.observers.remove(observe)
        for archive in archives:
            archive.close()
    return figures, described


# Every figure family drawn once on every archive of setUpModule (the label checks read all of them;
# the tests of one family on one archive take their figures from here rather than draw them again).
_ALL_DRAWN = {}


def drawn(family_draw, path):
    """(Figure records, descriptions by file) of one figure family on all the test's archives, of the
    figures of the archive `path` only (named by its study, figures_common.slug)."""
    if family_draw not in _ALL_DRAWN:
        _ALL_DRAWN[family_draw] = draw(family_draw, [GRID, FLYING, OPEN_LOOP, LANDING, MORRIS, DISPERSION])
    figures, described = _ALL_DRAWN[family_draw]
    with h5py.File(path, "r") as f:
        study = figures_common.slug(str(f.attrs["study_name"]))
    mine = [figure for figure in figures if study in figure.file]
    return mine, {figure.file: described[figure.file] for figure in mine}


class Figures(unittest.TestCase):
    """The figure fixes of issue 19, checked on the figures as drawn."""

    def test_stability_map_legend_clear_of_the_maps_and_the_phugoid_panel(self):
        figures, described = drawn(figures_maps.draw, GRID)
        self.assertEqual(len(figures), 2)  # one per h_derivatives value
        for figure in figures:
            d = described[figure.file]
            self.assertEqual(len(d["maps"]), 2, "σ and the phugoid's own margin")
            self.assertIn("phugoid", " ".join(title for title, _ in d["axes"]))
            self.assertEqual(len(d["legends"]), 1)
            texts, legend = d["legends"][0]
            for box in d["maps"]:
                self.assertFalse(legend.overlaps(box), f"the legend covers a map: {texts}")
            self.assertTrue(any(t.startswith("last table row (13.37 m)") for t in texts), texts)
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
        figures, described = draw(figures_modes.draw, [near, paper])
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
        figures, _ = draw(figures_modes.draw, [near])
        self.assertIn("at u0 = 31.5 m/s, the nearest of its speeds to the paper's 32.0208 m/s", figures[0].caption)

    def test_flying_qualities_say_where_each_level_is_lost(self):
        figures, described = drawn(figures_levels.draw, FLYING)
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
        styles = figures_open_loop._distinct_styles(figures_open_loop.MAX_OPEN_LOOP_LINES)
        for (a, style_a), (b, style_b) in itertools.combinations(styles, 2):
            if style_a == style_b:
                self.assertGreaterEqual(float(np.linalg.norm(np.subtract(a[:3], b[:3]))), MIN_LINE_COLOUR_DISTANCE)
        figures, described = drawn(figures_open_loop.draw, OPEN_LOOP)
        lines = [(colour, style) for title, label, colour, style in described[figures[0].file]["lines"]
                 if title == "whole run" and label.startswith("H0 =")]
        self.assertEqual(len(lines), 4)
        self.assertEqual(len(set((str(c), s) for c, s in lines)), 4)

    def test_landing_legend_names_the_wheel_contact_line(self):
        figures, described = drawn(figures_landing.draw, LANDING)
        texts = [t for legend, _ in described[figures[0].file]["legends"] for t in legend]
        self.assertIn("wheel contact (0.788 m)", texts)


    def test_no_label_shows_a_float_of_more_than_four_digits_and_every_legend_is_in_its_figure(self):
        """Every figure family on every archive of the test: legends, ticks and axis labels."""
        offending, seen, outside = [], 0, []
        for family in report_figures.families():
            drawn(family.draw, GRID)
            _, described = _ALL_DRAWN[family.draw]
            for name, d in described.items():
                for where, text in d["texts"]:
                    seen += 1
                    for token in NUMBER.findall(text):
                        if significant_digits(token) > MAX_LABEL_DIGITS:
                            offending.append(f"{name}: {where} {text!r} ({token})")
                frame = d["figure_box"]
                for texts, box in d["legends"]:
                    if box.x0 < frame.x0 - LEGEND_SLACK_PX or box.x1 > frame.x1 + LEGEND_SLACK_PX:
                        outside.append(f"{name}: legend {texts[:2]} spans x {box.x0:.0f}-{box.x1:.0f} of 0-{frame.x1:.0f}")
        self.assertGreater(seen, 100)
        self.assertEqual(offending, [], "\n".join(offending))
        self.assertEqual(outside, [], "\n".join(outside))

    def test_the_check_sees_a_long_float(self):
        for token, digits in (("-15.433333", 8), ("2.5935", 5), ("13.37", 4), ("0.0125", 3), ("2000", 1),
                              ("1.50", 3), ("−0.002", 1), ("1e-05", 1)):
            self.assertEqual([significant_digits(t) for t in NUMBER.findall(f"x = {token} m")], [digits], token)
        self.assertEqual(NUMBER.findall("scale.CMalpha (3.2.1.2)"), ["3.2"])

    def test_dispersion_panels_in_a_grid_named_in_words(self):
        figures, described = drawn(figures_dispersion.draw, DISPERSION)
        self.assertEqual(len(figures), 3)  # the ECDFs, the footprint, the limits
        ecdf = described[next(f.file for f in figures if f.file.endswith("_ecdf.png"))]
        panels = [box for title, box in ecdf["axes"] if title]
        with h5py.File(DISPERSION, "r") as f:
            columns_written = list(f["analysis/dispersion"].attrs["columns"])
        self.assertEqual(len(panels), len(columns_written))  # one panel per quantity
        self.assertLessEqual(len({round(box.x0) for box in panels}), MAX_DISPERSION_COLUMNS)
        self.assertLessEqual(ecdf["size"][0], PAGE_COLUMN_PX)
        for box in panels:
            self.assertGreaterEqual(box.width, MIN_DISPERSION_PANEL_PX)
        # The groups in the study's words: the winds in knots with their direction, from the archive's
        # values (u_g, m/s; negative is a headwind) and the definition of the knot.
        with h5py.File(DISPERSION, "r") as f:
            winds = np.unique(f["design/wind_20ft_mps"][...])
        expected = {f"W20 = {round(-w / KNOT_MPS):d} kt headwind" for w in winds}
        self.assertEqual(expected, {"W20 = 15 kt headwind", "W20 = 30 kt headwind"})
        for figure in figures:
            texts = [text for where, text in described[figure.file]["texts"] if where in ("legend", "x tick")]
            named = {e for e in expected if any(text.startswith(e) for text in texts)}
            self.assertEqual(named, expected, (figure.file, texts))
            self.assertFalse(any("wind_20ft_mps" in text for text in texts), texts)


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

    def test_a_figure_only_when_its_data_exist_and_a_line_where_not(self):
        out_dir = os.path.join(WORK, "landing_only")
        result = run("report", LANDING, "-o", out_dir, "-q")
        self.assertEqual(result.returncode, 0, result.stderr)
        page, text = parse(os.path.join(out_dir, "index.html"))
        self.assertEqual([i["src"].split("_")[0] for i in page.images], ["landing"])
        self.assertEqual(sorted(f for f in os.listdir(out_dir) if f.endswith(".png")),
                         [i["src"] for i in page.images])
        # Every section is there; one without data says so in one line, and names what writes it.
        sections = page_sections(text)
        for anchor in ("map", "boundary", "flying_qualities", "locus", "open_loop", "sensitivity", "dispersion"):
            with self.subTest(section=anchor):
                content = sections[anchor]
                self.assertNotIn("<img", content)
                absent = re.findall(r'<p class="absent">(.*?)</p>', content, re.S)
                self.assertEqual(len(absent), 1, content)
                self.assertNotIn("\n", absent[0])
                self.assertRegex(absent[0], r"^No archive of this report ")
        self.assertIn("<img", sections["landing"])
        self.assertNotIn('class="absent"', sections["landing"])

    def test_claims_cells_are_short_and_about_their_own_archives(self):
        _, text = parse(self.index)
        cells = claim_cells(text)
        self.assertGreaterEqual(len(cells), 5 * 4)
        for cell in cells:
            self.assertLessEqual(len(cell), MAX_CLAIM_CELL_CHARS, cell[:300] + "...")
        # The landing row is about the paper's landing study only (not the dispersion's 128 landings):
        # one line per plant, with what h5py reads of it.
        row = next(r for r in claim_rows(text) if "reaches the runway" in r[0])
        with h5py.File(LANDING, "r") as f:
            on = f["design/h_derivatives"][...] == 1
            touchdown, sink = f["results/landing/touchdown_time_s"][...], f["results/landing/touchdown_sink_rate_mps"][...]
        engine = row[2]
        self.assertEqual(engine.count("landed at"), 2)
        for i, words in ((int(np.nonzero(on)[0][0]), "with"), (int(np.nonzero(~on)[0][0]), "without")):
            self.assertIn(f"{words} h-derivatives: landed at {touchdown[i]:.5g} s, sink rate {sink[i]:.4g} m/s", engine)
        self.assertIn("from landing.h5", engine)
        self.assertNotIn("dispersion.h5", engine)

    def test_every_readme_section_is_in_the_report_or_says_why_not(self):
        headings, fenced = [], False
        with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
            for line in f:
                fenced ^= line.startswith("```")
                if line.startswith("## ") and not fenced:
                    headings.append(line[3:].strip())
        unmapped = [h for h in headings if h not in README_IN_REPORT and h not in README_NOT_IN_REPORT]
        self.assertEqual(unmapped, [], "README sections the report test does not know: add each to README_IN_REPORT "
                                       "(the report sections that show it) or README_NOT_IN_REPORT (why none)")
        stale = [h for h in list(README_IN_REPORT) + list(README_NOT_IN_REPORT) if h not in headings]
        self.assertEqual(stale, [], "sections README no longer has")
        # On the demo-like archives, every section README shows is in the page with its figure or table.
        sections = page_sections(parse(self.index)[1])
        for heading, anchors in README_IN_REPORT.items():
            for anchor in anchors:
                with self.subTest(readme=heading, section=anchor):
                    self.assertIn(anchor, sections)
                    self.assertNotIn('class="absent"', sections[anchor])
                    self.assertRegex(sections[anchor], r"<img |<table")

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

    def test_the_report_run_by_hand_is_checked_by_the_engine(self):
        # report.py started by hand (not by `gesweep report`) still refuses what every command refuses,
        # with the engine's own line: `gesweep check` is its one validator (docs/report.md, "One reader").
        foreign = os.path.join(WORK, "foreign.h5")
        with h5py.File(foreign, "w") as f:
            f.attrs["format"] = "gesweep-archive"  # the format's name, but none of its layout
            f.create_dataset("runs/status", data=np.zeros(3, dtype=np.int8))
        engine = run("query", foreign)
        self.assertNotEqual(engine.returncode, 0, engine.stdout + engine.stderr)
        with self.assertRaises(ValueError) as refused:
            report_data.open_archives([LANDING, foreign])
        self.assertEqual("gesweep: error: " + str(refused.exception), engine.stderr.strip())
        # What the engine says of a good archive is what the report then reads.
        archives = report_data.open_archives([LANDING])
        try:
            self.assertFalse(archives[0].snapshot)
            self.assertEqual(archives[0].notes, [])
            self.assertEqual(archives[0].run_count, int(h5py.File(LANDING, "r").attrs["run_count"]))
        finally:
            for archive in archives:
                archive.close()

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
        # No cell of the claims table is taller than a screen (the evidence behind a claim is collapsed).
        self.assertGreaterEqual(len(layout["cells"]), 5 * 4)
        self.assertLess(max(layout["cells"]), SCREEN_HEIGHT, layout["cells"])
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
  var out = {height: document.documentElement.scrollHeight, images: [], cells: []};
  document.querySelectorAll("table.claims td").forEach(function (td) {
    out.cells.push(td.getBoundingClientRect().height);
  });
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
