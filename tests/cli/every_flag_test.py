#!/usr/bin/python3
"""Every flag of every command is checked (issue 26, item 4), with no flag left out.

The flags come from the CLI itself (`gesweep --list-flags`, hidden: it walks the CLI11 subcommands,
aliases included). Each is one of:
- a switch (takes no value): nothing to range-check;
- checked against the limits table ("LIMIT:<entry>", AddLimitedOption / AddExactIntegerOption): the
  test reads the entry from `gesweep limits --format json` and gives a value just past each end (the
  bound itself when the bound is excluded; for a whole entry one past it, and a fraction), past a
  double's range, and NaN (never an input, an "automatic" setting's included: docs/limits.md); each
  must be refused with exit 2 and one line "command line: FLAG = VALUE: expected ...";
- a named choice ("CHOICE:<flag>"): a name nobody defined must be refused the same way;
- declared below: NOT_NUMERIC (paths, names, expressions, positionals; with the reason), or
  LISTS (numbers checked after parsing, each given its bad values here).
A flag that is none of these fails the test: a new flag must be classified here.

Usage: every_flag_test.py BUILD/gesweep
"""
import json
import os
import subprocess
import sys
import tempfile
import unittest

GESWEEP = os.path.abspath(sys.argv.pop(1))
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
ANCE = os.path.join(REPO, "studies", "aircraft", "ance.toml")

# What each command needs to parse (its required flags and positionals), before the flag under test.
# A flag's check runs while CLI11 parses, before the command does anything; the inputs exist so that a
# command checking them after parsing would still reach the flag's own check first.
BASE = {
    "boundary": ["--aircraft", ANCE, "--speed-mps", "32"],
    "check": ["{archive}"],
    "columns": [],
    "dispersion": ["{archive}"],
    "land": ["--aircraft", ANCE, "--summary-only"],
    "limits": [],
    "merge": ["{archive}", "-o", "{out}/merged.h5"],
    "modes": ["--aircraft", ANCE, "--speed-mps", "32"],
    "query": ["{archive}"],
    "report": ["{archive}", "-o", "{out}/report"],
    "risk": ["{study}", "-o", "{out}/risk.h5"],
    "run": ["{study}", "-o", "{out}/out.h5"],
    "sensitivity": ["{archive}", "--output", "x"],
    "simulate": ["--aircraft", ANCE, "--height-m", "40", "--speed-mps", "52.21", "--summary-only"],
}

# A flag that excludes one of BASE's: its own base.
BASE_OF = {("boundary", "--speeds-mps"): ["--aircraft", ANCE]}

# Flags that take no number: a path, a name, an expression, a positional. (command, first name): why.
NOT_NUMERIC = {
    ("boundary", "--aircraft"): "path", ("boundary", "--archive"): "path", ("boundary", "--by"): "column name",
    ("boundary", "--format"): "format name, checked by RequireFormat",
    ("check", "archives"): "positional paths", ("check", "--format"): "format name",
    ("columns", "--aircraft"): "path",
    ("dispersion", "archive"): "positional path", ("dispersion", "--columns"): "column names",
    ("dispersion", "--limit"): "a column's bound 'name<value' (its number parsed and checked with it)",
    ("dispersion", "--group-by"): "column name",
    ("land", "--aircraft"): "path", ("land", "--format"): "format name",
    ("limits", "--format"): "format name",
    ("merge", "archives"): "positional paths", ("merge", "-o"): "path",
    ("modes", "--aircraft"): "path", ("modes", "--format"): "format name",
    ("query", "archive"): "positional path", ("query", "--where"): "expression (its own parser, fuzzed)",
    ("query", "--aggregate"): "statistics expressions", ("query", "--sort"): "column name",
    ("query", "--columns"): "column names",
    ("query", "--group-by"): "column names",
    ("report", "archives"): "positional paths", ("report", "-o"): "path", ("report", "--title"): "text",
    ("risk", "input"): "positional path", ("risk", "-o"): "path",
    ("run", "study"): "positional path", ("run", "-o"): "path",
    ("run", "--merge"): "name: virtual or copy",
    ("sensitivity", "archive"): "positional path", ("sensitivity", "--output"): "column name",
    ("sensitivity", "--method"): "name: sobol or morris (none: the design's own)",
    ("simulate", "--aircraft"): "path", ("simulate", "--format"): "format name",
}

# Numbers given as a list or a pattern, checked after parsing: (command, first name) -> bad values
# (one past each end of their range), each refused with one line naming the flag.
LISTS = {
    ("boundary", "--speeds-mps"): ["0.5", "301", "30,1e308", "30,nan"],
    ("modes", "--heights-m"): ["0", "11001", "-1", "2,nan"],
    ("land", "--q-weights"): ["-1", "1e13", "1,nan"],
    ("dispersion", "--percentiles"): ["-1", "101", "nan"],
    ("dispersion", "--tail-probabilities"): ["0", "1", "nan"],
    ("run", "--shard"): ["-1/2", "2/2", "0/0", "1.5/2", "0/18446744073709551617"],
}


def gesweep(*args, timeout=60):
    return subprocess.run([GESWEEP, *args], capture_output=True, text=True, timeout=timeout)


def list_flags():
    done = gesweep("--list-flags")
    assert done.returncode == 0, done.stderr
    flags = []
    for line in done.stdout.splitlines():
        command, names, kind, visibility, check = line.split("\t")
        flags.append((command, names.split(","), kind, visibility, check))
    return flags


def number(value):
    return repr(float(value)) if not float(value).is_integer() or abs(value) >= 1e16 else str(int(value))


def past_each_end(limit):
    """Values just past each end of a limits-table entry (the bound itself when it is excluded)."""
    low, high = limit["minimum"], limit["maximum"]
    if limit.get("whole"):
        values = [str(int(low) - 1), str(int(high) + 1), str(int(low)) + ".5"]
    else:
        values = [number(low) if limit["minimum_exclusive"] else number(low - max(abs(low) * 1e-6, 1e-9))]
        if not limit["allows_infinity"]:
            values.append(number(high) if limit["maximum_exclusive"] else number(high + max(abs(high) * 1e-6, 1e-9)))
        else:
            values.append("-inf")
    values.append("1e400")
    return values


class EveryFlag(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.study = os.path.join(cls.tmp.name, "study.toml")
        with open(cls.study, "w") as f:
            f.write(f'format_version = 1\nname = "flags"\naircraft = "{ANCE}"\n[analyses.modes]\n'
                    "[parameters]\nspeed_mps = 32.0\nheight_m = 3.0\n")
        cls.archive = os.path.join(cls.tmp.name, "a.h5")
        done = gesweep("run", cls.study, "-o", cls.archive, "--quiet")
        assert done.returncode == 0, done.stderr
        cls.flags = list_flags()
        cls.limits = {e["name"]: e for e in json.loads(gesweep("limits", "--format", "json").stdout)["limits"]}

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def base(self, command, out, flag=None):
        args = BASE_OF.get((command, flag), BASE[command])
        return [a.replace("{archive}", self.archive).replace("{study}", self.study).replace("{out}", out)
                for a in args]

    def refused(self, command, flag, value, fragment=None):
        """The problems of `gesweep COMMAND BASE FLAG VALUE`: [] when it exits 2 with one line naming the
        flag (and `fragment`)."""
        with tempfile.TemporaryDirectory() as out:
            done = gesweep(command, *self.base(command, out, flag), flag, value)
            left = os.listdir(out)
        lines = done.stderr.strip().splitlines()
        # The flag and the value as typed, then what was expected (or that the number is past a double).
        wanted = fragment if fragment is not None else f"command line: {flag} = {value.strip()}: "
        problems = []
        if done.returncode != 2:
            problems.append(f"exit {done.returncode}")
        if len(lines) != 1 or wanted not in lines[0]:
            problems.append(f"stderr {done.stderr.strip()[:300]!r}, expected one line with {wanted!r}")
        if left:
            problems.append(f"left {left}")
        return [f"{command} {flag} {value!r}: {'; '.join(problems)}"] if problems else []

    def test_the_listing_covers_every_command(self):
        commands = {flag[0] for flag in self.flags}
        self.assertEqual(commands, set(BASE), "a command was added or removed: give it a BASE line")
        self.assertGreater(len(self.flags), 100)

    def test_every_flag_is_classified(self):
        unclassified = []
        for command, names, kind, _, check in self.flags:
            key = (command, names[-1] if names[0].startswith("-") and not names[0].startswith("--") else names[0])
            if kind == "switch" or check.startswith("LIMIT:") or check.startswith("CHOICE:"):
                continue
            if (command, names[0]) in NOT_NUMERIC or key in NOT_NUMERIC or (command, names[0]) in LISTS:
                continue
            unclassified.append(f"{command} {','.join(names)} ({kind}, check {check!r})")
        self.assertEqual(unclassified, [], "flags nobody classified: check them against the limits table, or "
                                           "declare them in NOT_NUMERIC or LISTS")
        declared = {(c, n[0]) for c, n, *_ in self.flags}
        stale = sorted(k for k in list(NOT_NUMERIC) + list(LISTS) if k not in declared)
        self.assertEqual(stale, [], "declared flags the CLI no longer has")

    def test_every_limited_flag_refuses_past_each_end(self):
        problems = []
        checked = 0
        for command, names, kind, _, check in self.flags:
            if not check.startswith("LIMIT:"):
                continue
            limit = self.limits[check[len("LIMIT:"):]]
            flag = names[-1]  # the long name (a short name comes first)
            for value in past_each_end(limit):
                problems += self.refused(command, flag, value)
                checked += 1
            problems += self.refused(command, flag, "nan")
            checked += 1
        self.assertGreater(checked, 200)
        self.maxDiff = None
        self.assertEqual(problems, [])

    def test_every_choice_refuses_an_unknown_name(self):
        problems = []
        for command, names, kind, _, check in self.flags:
            if check.startswith("CHOICE:"):
                problems += self.refused(command, names[-1], "no-such-name",
                                         f"command line: {names[-1]} = 'no-such-name': expected ")
        self.maxDiff = None
        self.assertEqual(problems, [])

    def test_every_listed_number_refuses_past_each_end(self):
        problems = []
        for (command, flag), values in LISTS.items():
            for value in values:
                problems += self.refused(command, flag, value, fragment=f"command line: {flag} = ")
        self.maxDiff = None
        self.assertEqual(problems, [])

    def test_the_turbulence_intensity_is_range_checked(self):
        """Once never checked: --turbulence-sigma-w-mps 1e308 flew."""
        for command in ("simulate", "land"):
            self.assertEqual(self.refused(command, "--turbulence-sigma-w-mps", "1e308",
                                          "command line: --turbulence-sigma-w-mps = 1e308: expected a number in "
                                          "[0, 50] m/s"), [])


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
