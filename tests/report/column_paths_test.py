#!/usr/bin/python3
"""No script under scripts/report or scripts/peer spells out an archive column path (issue 15): every
path comes from the column manifest through scripts/lib/columns.py, every (analysis, name) they ask it
for is in the manifest (`gesweep columns --json` of the build, $GESWEEP_BINARY), and they ask with literal names, so that this test sees each one.
Also: the manifest module's lookups and its one-line error for an unknown name.
Run by ctest (tests/report/CMakeLists.txt).
"""
import ast
import glob
import os
import re
import sys
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPTS = sorted(glob.glob(os.path.join(ROOT, "scripts", "report", "*.py"))
                 + glob.glob(os.path.join(ROOT, "scripts", "peer", "*.py")))
sys.path.insert(0, os.path.join(ROOT, "scripts", "lib"))
os.environ.pop("GESWEEP_COLUMNS_MANIFEST", None)  # the engine's manifest, not a test's file
import columns  # noqa: E402

# A string that begins with a per-run group and a name: an archive column path ("results/modes/...",
# f"series/{analysis}/...", "runs/status", "design/height_m").
PATH_START = re.compile(r"^/?(runs|design|results|series)/")
# A path inside a longer text (a caption, an error message) of an analysis the manifest has.
PATH_INSIDE = re.compile(r"\b(results|series)/(%s)/" % "|".join(map(re.escape, columns.analyses())))
# The lookups of scripts/lib/columns.py that take (analysis, name[, series]) or one name.
COLUMN_LOOKUPS = {"path", "units", "description", "levels", "column"}
ONE_NAME_LOOKUPS = {"analysis", "time_axis", "design_path", "runs_path"}


def docstrings(tree):
    """The nodes of the module's, classes' and functions' docstrings (prose, not paths)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
                out.add(id(first.value))
    return out


def literal_paths_in(tree):
    """(line, text) of every string literal of a parsed script that is or holds a column path."""
    prose = docstrings(tree)
    # An f-string is checked whole: its literal pieces are not checked again.
    pieces = {id(v) for node in ast.walk(tree) if isinstance(node, ast.JoinedStr) for v in node.values}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in prose | pieces:
            if PATH_START.match(node.value) or PATH_INSIDE.search(node.value):
                found.append((node.lineno, node.value))
        elif isinstance(node, ast.JoinedStr) and node.values:
            first = node.values[0]
            if isinstance(first, ast.Constant) and PATH_START.match(first.value):
                found.append((node.lineno, ast.unparse(node)))
    return found


def literal_paths(path):
    """literal_paths_in of a script file."""
    with open(path, encoding="utf-8") as f:
        return literal_paths_in(ast.parse(f.read(), path))


def lookups(path):
    """(line, function, positional arguments, keyword arguments) of every call columns.<lookup>(...)."""
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read(), path)
    out = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and isinstance(node.func.value, ast.Name) and node.func.value.id == "columns"
                and node.func.attr in COLUMN_LOOKUPS | ONE_NAME_LOOKUPS):
            out.append((node.lineno, node.func.attr, node.args, node.keywords))
    return out


# A string that is the path of an /analysis product or of a group of a subset-simulation archive
# ("analysis/boundary", "/analysis/dispersion", f"analysis/{name}", "subset/evaluations"): the shared
# reader finds them in the manifest's layout (`products`, `subset_archive`).
PRODUCT_PATH = re.compile(r"^/?(analysis|subset)(/|$)")
# The run-status names, whose codes come from the manifest's run_status (RunStatus's names table).
STATUS_NAMES = {"pending", "ok", "failed"}


def literal_product_paths_in(tree):
    """(line, text) of every string literal (or f-string) of a parsed script that is a product path."""
    prose = docstrings(tree)
    pieces = {id(v) for node in ast.walk(tree) if isinstance(node, ast.JoinedStr) for v in node.values}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in prose | pieces:
            if PRODUCT_PATH.match(node.value):
                found.append((node.lineno, node.value))
        elif isinstance(node, ast.JoinedStr) and node.values:
            first = node.values[0]
            if isinstance(first, ast.Constant) and PRODUCT_PATH.match(first.value):
                found.append((node.lineno, ast.unparse(node)))
    return found


def _integers(node):
    """Whether `node` is an integer literal (or a tuple, list or set of them): a code, not a name."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        node = node.operand
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return bool(node.elts) and all(_integers(e) for e in node.elts)
    return isinstance(node, ast.Constant) and type(node.value) is int


def literal_status_codes_in(tree):
    """(line, text) of every place a parsed script spells a run-status code: a comparison of something
    named status with an integer, a name of a status bound to an integer, a status name mapped to one."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            named = [o for o in operands if isinstance(o, (ast.Name, ast.Attribute, ast.Subscript))]
            if any("status" in ast.unparse(o).lower() for o in named) and any(_integers(o) for o in operands):
                found.append((node.lineno, ast.unparse(node)))
        elif isinstance(node, ast.Assign) and _integers(node.value):
            names = " ".join(ast.unparse(t) for t in node.targets).lower()
            if "status" in names or any(name in names.split("_") for name in STATUS_NAMES):
                found.append((node.lineno, ast.unparse(node)))
        elif isinstance(node, ast.Dict):
            if any(isinstance(k, ast.Constant) and k.value in STATUS_NAMES and _integers(v)
                   for k, v in zip(node.keys, node.values)):
                found.append((node.lineno, ast.unparse(node)))
    return found


def parsed(path):
    with open(path, encoding="utf-8") as f:
        return ast.parse(f.read(), path)


def imports_h5py(source):
    """Whether Python `source` imports h5py (or a submodule of it)."""
    for node in ast.walk(ast.parse(source)):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                 else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
        if any(n.split(".")[0] == "h5py" for n in names):
            return True
    return False


class NoLiteralColumnPaths(unittest.TestCase):
    def test_scripts_spell_out_no_column_path(self):
        self.assertGreaterEqual(len(SCRIPTS), 5, SCRIPTS)
        found = [f"{os.path.relpath(p, ROOT)}:{line}: {text!r}" for p in SCRIPTS for line, text in literal_paths(p)]
        self.assertEqual(found, [], "column paths spelled out; ask scripts/lib/columns.py instead:\n" + "\n".join(found))

    def test_the_check_finds_a_path(self):
        # The checks above would see a path written in any of these ways.
        source = ('a = "results/modes/stability_margin_per_s"\nb = f"series/{x}/height_m"\n'
                  'c = "from results/landing/outcome of"\nd = "design/" + name\ne = "runs/status"\n')
        self.assertEqual(sorted(line for line, _ in literal_paths_in(ast.parse(source))), [1, 2, 3, 4, 5])
        # Prose is not a path: a docstring, and a path of an analysis the manifest does not have.
        self.assertEqual(literal_paths_in(ast.parse('"""Reads results/modes/stability_margin_per_s."""\n'
                                                    'x = "see results/other/thing"\n')), [])

    def test_one_reader_of_archive_files(self):
        # scripts/report opens archives only through the module gesweep.open_archive uses
        # (engine/python/gesweep/_hdf5.py), after the engine's check: none of its files imports h5py.
        report = [p for p in SCRIPTS if os.sep + "report" + os.sep in p]
        self.assertGreaterEqual(len(report), 5, report)
        importers = [os.path.relpath(p, ROOT) for p in report
                     if imports_h5py(open(p, encoding="utf-8").read())]
        self.assertEqual(importers, [], "read archives through report_data (gesweep's _hdf5), not h5py")
        # The check sees an import written in any of these ways, and not a mention in prose.
        for source in ("import h5py\n", "import numpy, h5py as h\n", "from h5py import File\n",
                       "def f():\n    import h5py.h5f\n"):
            self.assertTrue(imports_h5py(source), source)
        self.assertFalse(imports_h5py('"""Not h5py: import h5py is prose here."""\n'))

    def test_every_name_the_scripts_ask_for_is_in_the_manifest(self):
        asked, problems = [], []
        for path in SCRIPTS:
            where = os.path.relpath(path, ROOT)
            for line, function, args, keywords in lookups(path):
                literal = all(isinstance(a, ast.Constant) for a in args) and all(
                    isinstance(k.value, ast.Constant) for k in keywords)
                if not literal:
                    problems.append(f"{where}:{line}: columns.{function}(...) with a name this test cannot read; "
                                    f"use literal names")
                    continue
                values = [a.value for a in args]
                options = {k.arg: k.value.value for k in keywords}
                try:
                    getattr(columns, function)(*values, **options)
                except columns.UnknownColumn as error:
                    problems.append(f"{where}:{line}: {error}")
                asked.append((function, tuple(values), tuple(sorted(options.items()))))
        self.assertEqual(problems, [], "\n".join(problems))
        # The report does ask: its figures and claims read at least these through the manifest.
        names = {v for _, v, _ in asked}
        for expected in (("modes", "stability_margin_per_s"), ("open_loop", "min_height_time_s"),
                         ("landing", "outcome"), ("open_loop", "height_m")):
            self.assertIn(expected, names)


class NoLiteralStatusCodesOrProductPaths(unittest.TestCase):
    """scripts/report spells no run-status code and no /analysis (or subset-simulation) path: the shared
    reader (engine/python/gesweep/_hdf5.py) finds them in the manifest (issue 29, item 4)."""

    def report_scripts(self):
        report = [p for p in SCRIPTS if os.sep + "report" + os.sep in p]
        self.assertGreaterEqual(len(report), 5, report)
        return report

    def test_no_product_path_spelled_out(self):
        found = [f"{os.path.relpath(p, ROOT)}:{line}: {text!r}" for p in self.report_scripts()
                 for line, text in literal_product_paths_in(parsed(p))]
        self.assertEqual(found, [], "/analysis paths spelled out; read products through report_data's "
                                    "shared reader (archive.boundary(), .dispersion(), ...):\n" + "\n".join(found))

    def test_no_status_code_spelled_out(self):
        found = [f"{os.path.relpath(p, ROOT)}:{line}: {text}" for p in self.report_scripts()
                 for line, text in literal_status_codes_in(parsed(p))]
        self.assertEqual(found, [], "run-status codes spelled out; use archive.ok, .complete, .counts() or the "
                                    "layout's status_code(name):\n" + "\n".join(found))

    def test_the_checks_find_what_they_look_for(self):
        source = ('a = "analysis/boundary"\nb = f"analysis/{name}"\nc = "/analysis/dispersion"\n'
                  'd = "subset/evaluations"\ne = "analysis"\n')
        self.assertEqual(sorted(line for line, _ in literal_product_paths_in(ast.parse(source))), [1, 2, 3, 4, 5])
        # Prose is not a path: a docstring, a legend naming the product, a word.
        self.assertEqual(literal_product_paths_in(ast.parse(
            '"""Reads analysis/boundary."""\nx = "H* refined (/analysis/boundary)"\ny = "analysis of it"\n')), [])
        source = ('x = archive.status == 1\nSTATUS_OK = 1\nSTATUS_PENDING, STATUS_OK = 0, 1\n'
                  'y = status[rows] != 0\nz = e["status"] in (1, 2)\nc = {"ok": 1}\nok_code = 1\n'
                  'w = 2 == run_status\n')
        self.assertEqual(sorted(line for line, _ in literal_status_codes_in(ast.parse(source))),
                         [1, 2, 3, 4, 5, 6, 7, 8])
        # A code asked by name, and counts of runs, are not codes.
        self.assertEqual(literal_status_codes_in(ast.parse(
            'x = status == layout.status_code("ok")\nok, failed, pending = archive.counts()\n'
            'n = len(statuses) > 0\n')), [])


class ColumnsModule(unittest.TestCase):
    def test_lookups(self):
        self.assertEqual(columns.path("modes", "stability_margin_per_s"), "results/modes/stability_margin_per_s")
        self.assertEqual(columns.path("open_loop", "height_m", series=True), "series/open_loop/height_m")
        self.assertEqual(columns.units("open_loop", "min_height_time_s"), "s")
        self.assertEqual(columns.levels("open_loop", "end_event"), ["touchdown", "stall", "time_limit", "diverged"])
        self.assertEqual(columns.time_axis("landing"), "series/landing/time_s")
        self.assertEqual(columns.design_path("speed_mps"), "design/speed_mps")
        self.assertEqual(columns.runs_path("status"), "runs/status")
        self.assertEqual(columns.groups(), ("runs/", "design/", "results/", "series/"))
        rated = {entry["name"]: (overall["name"], [p["name"] for p in parts])
                 for entry, overall, parts in columns.ratings()}
        self.assertEqual(rated, {"flying_qualities": ("level", ["short_period_level", "phugoid_level"])})

    def test_unknown_names_are_one_clear_line(self):
        for call, words in ((lambda: columns.path("modes", "no_such_column"),
                             ("modes", "no results column 'no_such_column'", "stability_margin_per_s")),
                            (lambda: columns.path("open_loop", "min_height_m", series=True),
                             ("open_loop", "no series column 'min_height_m'", "height_m")),
                            (lambda: columns.units("no_such_analysis", "x"), ("no analysis 'no_such_analysis'",
                                                                               "modes")),
                            (lambda: columns.design_path("no_such_parameter"), ("no_such_parameter",))):
            with self.assertRaises(columns.UnknownColumn) as raised:
                call()
            text = str(raised.exception)
            self.assertNotIn("\n", text)
            self.assertIn("columns --json", text)  # where the manifest came from
            for word in words:
                self.assertIn(word, text)


if __name__ == "__main__":
    unittest.main(verbosity=2)
