#!/usr/bin/python3
"""The tour notebook runs (issue 30): notebooks/gesweep_tour.ipynb is executed, in a temporary copy, by
Debian's nbclient (python3-nbclient, in GESWEEP_PACKAGES) with the python3 kernel (python3-ipykernel)
and the module of this build (PYTHONPATH from ctest), each cell within a time limit. Its archives go to
a temporary folder ($GESWEEP_NOTEBOOK_OUTPUT); the repository is left as it was: the committed notebook
is stripped (no outputs, no execution counts) and stays byte for byte what it was.
The checks on its outputs: no cell fails (the notebook's own check of H* against the table rows where σ
changes sign included), both figures are drawn, and H* as it prints it is what `gesweep boundary`
gives through the command line for the same aircraft and speed.
Run by ctest (tests/notebook/CMakeLists.txt) with the gesweep binary as the first argument.
"""
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import nbclient
import nbformat

GESWEEP = os.path.abspath(sys.argv.pop(1))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
NOTEBOOK = os.path.join(ROOT, "notebooks", "gesweep_tour.ipynb")
# A cell may take this long (s): the slowest, 32 turbulent landings, takes about 2.5 s on a loaded
# 2-core machine; the kernel's start is not a cell.
CELL_TIMEOUT_S = 120
# The kernel of Debian's /usr/bin/python3 (python3-ipykernel: /usr/share/jupyter/kernels/python3).
KERNEL = "python3"
# The notebook prints H* with 4 decimals (m): it agrees with the command's when within half a unit.
PRINTED_HALF_UNIT_M = 0.5e-4
PAPER_SPEED_MPS = 32.0208


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


class Tour(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="gesweep_notebook_test_")
        cls.before = digest(NOTEBOOK)
        cls.results_before = os.path.exists(os.path.join(ROOT, "results", "notebook"))
        copy = os.path.join(cls.work, "gesweep_tour.ipynb")
        shutil.copy(NOTEBOOK, copy)
        cls.committed = nbformat.read(NOTEBOOK, as_version=4)
        cls.executed = nbformat.read(copy, as_version=4)
        os.environ.update({"GESWEEP_ROOT": ROOT, "GESWEEP_NOTEBOOK_OUTPUT": os.path.join(cls.work, "out"),
                           "JUPYTER_RUNTIME_DIR": os.path.join(cls.work, "runtime"),
                           "IPYTHONDIR": os.path.join(cls.work, "ipython"), "MPLCONFIGDIR": os.path.join(cls.work, "mpl"),
                           "PYDEVD_DISABLE_FILE_VALIDATION": "1"})
        client = nbclient.NotebookClient(cls.executed, timeout=CELL_TIMEOUT_S, kernel_name=KERNEL,
                                         resources={"metadata": {"path": cls.work}})
        cls.error = None
        try:
            client.execute()
        except nbclient.exceptions.CellExecutionError as error:
            cls.error = str(error)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def outputs(self, kind):
        return [o for cell in self.executed.cells if cell.cell_type == "code" for o in cell.outputs
                if o.output_type == kind or kind in o.get("data", {})]

    def text(self):
        return "".join(o.text for o in self.outputs("stream"))

    def test_the_committed_notebook_is_stripped(self):
        for cell in self.committed.cells:
            if cell.cell_type == "code":
                self.assertEqual(cell.outputs, [], cell.source[:80])
                self.assertIsNone(cell.execution_count, cell.source[:80])

    def test_every_cell_runs(self):
        self.assertIsNone(self.error)
        self.assertGreaterEqual(sum(c.cell_type == "code" for c in self.executed.cells), 8)
        self.assertEqual(self.outputs("error"), [])

    def test_both_figures_and_the_archives(self):
        self.assertIsNone(self.error)
        self.assertEqual(len(self.outputs("image/png")), 2)  # the stability map and the landings' ECDFs
        for name in ("tour_map.h5", "tour_dispersion.h5"):
            self.assertTrue(os.path.isfile(os.path.join(self.work, "out", name)), name)

    def test_the_boundary_it_prints_is_the_commands(self):
        self.assertIsNone(self.error)
        match = re.search(r"H\* = ([0-9.]+) m \(H\*/b = ([0-9.]+)\), certified: True", self.text())
        self.assertIsNotNone(match, self.text())
        out = subprocess.run([GESWEEP, "boundary", "--aircraft", os.path.join(ROOT, "studies/aircraft/ance.toml"),
                              "--speed-mps", str(PAPER_SPEED_MPS), "--format", "json"],
                             capture_output=True, text=True, timeout=120)
        self.assertEqual(out.returncode, 0, out.stderr)
        command = json.loads(out.stdout)["boundaries"][0]["height_m"]
        self.assertLessEqual(abs(float(match.group(1)) - command), PRINTED_HALF_UNIT_M)

    def test_the_repository_is_left_as_it_was(self):
        self.assertEqual(digest(NOTEBOOK), self.before)
        self.assertEqual(os.path.exists(os.path.join(ROOT, "results", "notebook")), self.results_before)


if __name__ == "__main__":
    unittest.main(verbosity=2)
