"""tests/risk/risk_restart: splitting with restarts gives the same estimates on 1 and 2 threads, digit for
digit (each landing's tree is a function of the seed and its index), with retrials flown and a landing
scored, so the comparison is not empty; bad arguments (no thread, a cell the study lacks, lists of
different lengths, thresholds not ascending, a split below 1, too few arguments) are one line and exit 2.

    /usr/bin/python3 tests/risk/risk_restart_threads_test.py BUILD/tests/risk/risk_restart
"""

import re
import subprocess
import sys
import unittest

PROGRAM = sys.argv.pop(1) if len(sys.argv) > 1 else "build/tests/risk/risk_restart"
STUDY = "studies/bench/landing_risk_hard.toml"
ARGS = [STUDY, "1.83,2.2", "1", "40", "7", "1.0,1.5,1.83", "3,6,8"]


def run(*args):
    return subprocess.run([PROGRAM, *args], capture_output=True, text=True, timeout=600)


def estimates(output):
    """The estimate lines and the retrials, without the wall time."""
    lines = [line for line in output.splitlines() if line.startswith("run ")]
    retrials = re.findall(r"\((\d+) retrials\)", output)
    return lines, retrials


class RestartThreads(unittest.TestCase):
    def test_one_and_two_threads_give_the_same_estimates(self):
        one = run("--threads", "1", *ARGS)
        two = run("--threads", "2", *ARGS)
        self.assertEqual(one.returncode, 0, one.stderr)
        self.assertEqual(two.returncode, 0, two.stderr)
        lines_one, retrials_one = estimates(one.stdout)
        lines_two, retrials_two = estimates(two.stdout)
        self.assertEqual(len(lines_one), 2, one.stdout)
        self.assertEqual(lines_one, lines_two)
        self.assertEqual(retrials_one, retrials_two)
        # Not an empty comparison: branches were flown and the firm limit was scored.
        self.assertGreater(int(retrials_one[0]), 0, one.stdout)
        p = float(re.search(r"sink rate > 1.83 m/s: P = ([^,]+),", one.stdout).group(1))
        self.assertGreater(p, 0.0, one.stdout)

    def test_bad_arguments_are_one_line_and_exit_2(self):
        for args in (["--threads", "0", *ARGS], ["--cell", "1", *ARGS], [*ARGS[:5], "1.0,1.5", "3"], [*ARGS[:5], "1.5,1.0", "3,6"],
                     [*ARGS[:5], "1.0,1.5", "3,0.5"], [STUDY]):
            result = run(*args)
            self.assertEqual(result.returncode, 2, (args, result.stdout, result.stderr))
            self.assertEqual(len(result.stderr.strip().splitlines()), 1, (args, result.stderr))
            self.assertEqual(result.stdout, "", args)


if __name__ == "__main__":
    unittest.main()
