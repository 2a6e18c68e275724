#!/usr/bin/python3
"""End-to-end test of `gesweep report` (issue 6): small archives of the ANCE (a stability grid with its
refined boundary, a short Fig. 4 study, the paper's landing pair, a Morris sensitivity), rendered into
one page; every image the page references exists and is a non-blank PNG; the tables carry what h5py
reads from the same archives; a figure is drawn only when its data exist; a headless Chromium
screenshot of the page is taken (Debian's chromium, installed here when missing and possible, else
that one check is skipped with the reason).
Run by ctest (tests/report/CMakeLists.txt) with the gesweep binary as the first argument.
"""
import html.parser
import os
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

GESWEEP = os.path.abspath(sys.argv.pop(1))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
WORK = tempfile.mkdtemp(prefix="gesweep_report_test_")
ARCHIVES = os.path.join(WORK, "archives")
# A rendered figure or screenshot is "not blank" when its pixels vary at least this much (0..1 scale).
MIN_PIXEL_STD = 0.02
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync"]


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


def setUpModule():
    os.makedirs(ARCHIVES)
    global GRID, OPEN_LOOP, LANDING, MORRIS
    GRID = sweep("tests/query/boundary_grid.toml", "grid.h5")
    out = run("boundary", "--archive", GRID)
    assert out.returncode == 0, out.stderr
    OPEN_LOOP = sweep("tests/report/open_loop_small.toml", "open_loop.h5")
    LANDING = sweep("studies/paper/landing.toml", "landing.h5")
    MORRIS = sweep("studies/verification/morris_linear.toml", "morris.h5")
    run("sensitivity", MORRIS, "--output", "linear")  # a colleague's command; its absence only drops a figure


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
        for prefix in ("stability_map_", "root_locus", "open_loop_", "landing_"):
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

    def test_chromium_screenshot(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        browser = shutil.which("chromium")
        if browser is None:
            reason = install_chromium()
            browser = shutil.which("chromium")
            if browser is None:
                self.skipTest(f"no headless Chromium: {reason}")
        profile = tempfile.mkdtemp(prefix="gesweep_chromium_", dir=WORK)
        shot = os.path.join(WORK, "screenshot.png")
        width, height = 1280, 2400
        result = subprocess.run([browser, *CHROMIUM_FLAGS, f"--user-data-dir={profile}",
                                 f"--window-size={width},{height}", f"--screenshot={shot}",
                                 "file://" + os.path.abspath(self.index)],
                                capture_output=True, text=True, timeout=180)
        self.assertTrue(os.path.isfile(shot), result.stderr[-2000:])
        self.assertGreater(os.path.getsize(shot), 0)
        pixels = matplotlib.image.imread(shot)
        self.assertEqual(pixels.shape[:2], (height, width))
        self.assertGreater(float(np.std(pixels[..., :3])), MIN_PIXEL_STD, "the screenshot is blank")


def install_chromium():
    """Installs Debian's chromium with apt-get when run as root or with password-less sudo; returns
    why it could not otherwise."""
    if os.geteuid() == 0:
        prefix = []
    elif shutil.which("sudo") and subprocess.run(["sudo", "-n", "true"], capture_output=True).returncode == 0:
        prefix = ["sudo", "-n"]
    else:
        return "chromium is not installed and apt-get needs root (install the Debian package chromium)"
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    print("report_test: installing Debian's chromium for the screenshot check", file=sys.stderr)
    subprocess.run(prefix + ["apt-get", "update", "-qq"], capture_output=True, env=env, timeout=600)
    result = subprocess.run(prefix + ["apt-get", "install", "-y", "-qq", "--no-install-recommends", "chromium"],
                            capture_output=True, text=True, env=env, timeout=1200)
    if result.returncode != 0:
        return "apt-get install chromium failed: " + (result.stderr.strip().splitlines() or ["?"])[-1]
    return ""


if __name__ == "__main__":
    unittest.main(verbosity=2)
