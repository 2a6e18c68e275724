#!/usr/bin/python3
"""Tests of the Slurm scripts that need no Slurm (scripts/slurm; docs/cluster.md).

- shard lists and the shard count (scripts/slurm/lib/slurm_sweep.py);
- `submit --dry-run`: the sbatch commands it would run, and nothing written;
- bad input: one line on stderr, exit 2;
- the merge job on an OUT_DIR whose shards were run by hand with the real gesweep: it refuses while
  a shard is missing or incomplete and names it, then merges once all are there, into an archive
  equal to a single-process run (tests/slurm/compare_archives.py);
- the array task: it refuses a changed study, and passes SIGTERM on to gesweep, which leaves a
  closed, resumable archive.

The full path through a real Slurm is scripts/slurm/selftest (ctest label `slurm`).

Usage: slurm_scripts_test.py --gesweep BUILD/gesweep
"""

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SLURM = os.path.join(REPO, "scripts", "slurm")
sys.path.insert(0, os.path.join(SLURM, "lib"))
import slurm_sweep as ss  # noqa: E402

STUDY = os.path.join(REPO, "tests", "slurm", "tiny_study.toml")
# The tiny study's grid: 20 heights x 10 speeds x 2 h-derivative settings, counted by hand.
STUDY_RUNS = 20 * 10 * 2
# tests/slurm/requeue_study.toml: 40 speeds x 150 CLh scales.
SLOW_RUNS = 40 * 150
COMPARE = os.path.join(REPO, "tests", "slurm", "compare_archives.py")
GESWEEP = None


def run(command, **kwargs):
    return subprocess.run(command, capture_output=True, text=True, **kwargs)


def write_variant(path, *replacements):
    """Writes the tiny study to `path` with its aircraft made absolute and `replacements` applied."""
    with open(STUDY) as handle:
        text = handle.read()
    replacements = (('aircraft = "../../studies/aircraft/ance.toml"',
                     f'aircraft = "{os.path.join(REPO, "studies", "aircraft", "ance.toml")}"'),) + replacements
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new)
    with open(path, "w") as handle:
        handle.write(text)
    return path


class ShardListTest(unittest.TestCase):
    def test_format_compresses_ranges(self):
        self.assertEqual(ss.format_shard_list([0, 1, 2]), "0-2")
        self.assertEqual(ss.format_shard_list([6, 1, 4, 5]), "1,4-6")
        self.assertEqual(ss.format_shard_list([3]), "3")

    def test_parse_inverts_format(self):
        for indices in ([0], [1, 4, 5, 6], list(range(10)), [0, 2, 4, 9]):
            self.assertEqual(ss.parse_shard_list(ss.format_shard_list(indices), 10), indices)

    def test_parse_rejects_out_of_range_and_garbage(self):
        for text in ("3", "0-3", "2-1", "a", "1,,2", "-1"):
            with self.assertRaises(ss.UsageError, msg=text):
                ss.parse_shard_list(text, 3)


class ShardCountTest(unittest.TestCase):
    def test_tasks_given_is_capped_by_runs_and_array_size(self):
        self.assertEqual(ss.choose_shard_count(400, 3, 1, None, 1001), 3)
        self.assertEqual(ss.choose_shard_count(5, 8, 1, None, 1001), 5)  # no empty shard
        self.assertEqual(ss.choose_shard_count(10**6, 5000, 1, None, 1001), 1001)

    def test_default_cuts_the_estimate_into_task_hours(self):
        hour = ss.DEFAULT_TASK_SECONDS
        # 10 single-thread hours: 10 tasks of 1 thread, or 3 tasks of 4 threads (ceil 2.5).
        self.assertEqual(ss.choose_shard_count(10**6, None, 1, 10 * hour, 1001), 10)
        self.assertEqual(ss.choose_shard_count(10**6, None, 4, 10 * hour, 1001), 3)
        self.assertEqual(ss.choose_shard_count(10**6, None, 1, 0.5, 1001), 1)
        self.assertEqual(ss.choose_shard_count(0, None, 1, 0.0, 1001), 1)


class SubmitTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="gesweep-slurm-test.")

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def submit(self, *args):
        return run([os.path.join(SLURM, "submit"), *args, "--gesweep", GESWEEP])

    def test_dry_run_prints_the_array_and_the_merge_job(self):
        out_dir = os.path.join(self.tmp, "out")
        result = self.submit(STUDY, out_dir, "--tasks", "3", "--threads-per-task", "2", "--partition", "p1",
                             "--time", "00:10:00", "--dry-run", "--", "--account=a1")
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        array = next(line for line in lines if "--array=" in line)
        merge = next(line for line in lines if "--dependency=" in line)
        for expected in ("--array=0-2", "--cpus-per-task=2", "--requeue", "--open-mode=append",
                         "--partition=p1", "--time=00:10:00", "--account=a1",
                         os.path.join(SLURM, "shard_task"), STUDY, f"{out_dir} 3 2"):
            self.assertIn(expected, array)
        for expected in ("--dependency=afterok:<job-id>", "--kill-on-invalid-dep=no", "--partition=p1",
                         "--account=a1", os.path.join(SLURM, "merge_job"), f"{out_dir} 3"):
            self.assertIn(expected, merge)
        self.assertIn(f"gesweep-slurm: {STUDY_RUNS} runs in 3 shard(s) of at most 134 runs", result.stdout)
        self.assertFalse(os.path.exists(out_dir), "a dry run must write nothing")

    def test_more_tasks_than_runs_gives_one_run_per_shard(self):
        # A 2-run study: --tasks 5 becomes 2 shards (no empty shard) with a note.
        study = write_variant(os.path.join(self.tmp, "two.toml"),
                              ("linspace = [0.8, 14.0, 20]", "values = [2.0]"),
                              ("linspace = [26.0, 60.0, 10]", "values = [32.0]"))
        result = self.submit(study, os.path.join(self.tmp, "out"), "--tasks", "5", "--dry-run")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("--array=0-1", result.stdout)
        self.assertIn("using 2", result.stderr)

    def test_bad_input_is_one_line_and_exit_2(self):
        bad_study = write_variant(os.path.join(self.tmp, "bad.toml"), ("[output]", "[output]\nchunk_rnus = 3"))
        cases = {
            "missing study": ([os.path.join(self.tmp, "nope.toml"), self.tmp + "/o"], "no such file"),
            "bad --time": ([STUDY, self.tmp + "/o", "--time", "ten minutes"], "--time"),
            "bad --tasks": ([STUDY, self.tmp + "/o", "--tasks", "0"], "--tasks"),
            "bad study key": ([bad_study, self.tmp + "/o"], "chunk_rnus"),
        }
        for name, (args, needle) in cases.items():
            with self.subTest(name):
                result = self.submit(*args, "--dry-run")
                self.assertEqual(result.returncode, 2, result.stderr)
                self.assertEqual(len(result.stderr.strip().splitlines()), 1, result.stderr)
                self.assertIn(needle, result.stderr)

    def test_status_without_manifest_is_exit_2(self):
        result = run([os.path.join(SLURM, "status"), self.tmp])
        self.assertEqual(result.returncode, 2)
        self.assertIn(ss.MANIFEST_NAME, result.stderr)


class MergeJobTest(unittest.TestCase):
    """The merge job, run by hand on shards run by hand (what the array tasks would do)."""

    SHARDS = 3

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="gesweep-slurm-test.")
        self.out_dir = os.path.join(self.tmp, "out")
        os.makedirs(os.path.join(self.out_dir, "logs"))
        manifest = {
            "format": ss.MANIFEST_FORMAT, "name": "tiny", "study": STUDY, "study_sha256": ss.sha256_of(STUDY),
            "gesweep": GESWEEP, "out_dir": self.out_dir, "runs": STUDY_RUNS, "shards": self.SHARDS,
            "threads_per_task": 1, "sbatch_options": [], "submitted_utc": "", "jobs": [],
        }
        ss.write_manifest(self.out_dir, manifest)

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def shard_task(self, index):
        env = dict(os.environ, SLURM_ARRAY_TASK_ID=str(index))
        result = run([os.path.join(SLURM, "shard_task"), GESWEEP, STUDY, ss.sha256_of(STUDY), self.out_dir,
                      str(self.SHARDS), "1"], env=env)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)

    def merge_job(self):
        return run([os.path.join(SLURM, "merge_job"), SLURM, GESWEEP, self.out_dir, str(self.SHARDS)])

    def test_refuses_missing_shards_then_merges_equal_to_one_process(self):
        self.shard_task(0)
        refused = self.merge_job()
        self.assertNotEqual(refused.returncode, 0)
        self.assertIn("merge refused: incomplete shards: 1 (missing: no archive), 2 (missing: no archive)",
                      refused.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.out_dir, ss.MERGED_NAME)))

        self.shard_task(1)
        self.shard_task(2)
        status = run([os.path.join(SLURM, "status"), self.out_dir])
        self.assertEqual(status.returncode, 0, status.stderr)
        self.assertIn(f"3 of 3 shards complete ({STUDY_RUNS} runs in all)", status.stdout)
        merged = self.merge_job()
        self.assertEqual(merged.returncode, 0, merged.stdout + merged.stderr)

        reference = os.path.join(self.tmp, "reference.h5")
        result = run([GESWEEP, "run", STUDY, "-o", reference, "--threads", "2"])
        self.assertEqual(result.returncode, 0, result.stderr)
        compare = run(["/usr/bin/python3", COMPARE, reference, os.path.join(self.out_dir, ss.MERGED_NAME)])
        self.assertEqual(compare.returncode, 0, compare.stdout + compare.stderr)
        # The comparison can fail: a single shard is not the whole study.
        partial = run(["/usr/bin/python3", COMPARE, reference, ss.shard_path(self.out_dir, 0)])
        self.assertEqual(partial.returncode, 1, partial.stdout + partial.stderr)

    def test_task_passes_sigterm_to_gesweep_which_closes_a_resumable_archive(self):
        # Slurm's `scancel --batch` or a --signal=B:TERM reaches only the batch shell: shard_task
        # must pass it on, and gesweep must stop cleanly (exit 143) with its archive closed.
        slow = os.path.join(REPO, "tests", "slurm", "requeue_study.toml")
        manifest = ss.read_manifest(self.out_dir)
        manifest.update(study=slow, study_sha256=ss.sha256_of(slow), shards=1, runs=SLOW_RUNS)
        ss.write_manifest(self.out_dir, manifest)
        env = dict(os.environ, SLURM_ARRAY_TASK_ID="0")
        task = subprocess.Popen([os.path.join(SLURM, "shard_task"), GESWEEP, slow, ss.sha256_of(slow),
                                 self.out_dir, "1", "1"], env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        # The archive exists once gesweep has created it; give it a few batches more.
        deadline = time.monotonic() + 30
        while not os.path.exists(ss.shard_path(self.out_dir, 0)) and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.5)
        task.send_signal(signal.SIGTERM)  # to the shell only, not to gesweep
        stdout, stderr = task.communicate(timeout=60)
        self.assertEqual(task.returncode, 143, stdout + stderr)
        self.assertIn("stopped by signal 15", stderr)
        status = run([os.path.join(SLURM, "status"), self.out_dir])
        # Closed cleanly (not a snapshot) with some, not all, runs done.
        self.assertRegex(status.stdout, rf"shard 0: incomplete \([1-9][0-9]* of {SLOW_RUNS} runs\)\n", status.stdout)

    def test_task_refuses_a_changed_study(self):
        env = dict(os.environ, SLURM_ARRAY_TASK_ID="0")
        result = run([os.path.join(SLURM, "shard_task"), GESWEEP, STUDY, "0" * 64, self.out_dir,
                      str(self.SHARDS), "1"], env=env)
        self.assertEqual(result.returncode, 2)
        self.assertIn("changed since submission", result.stderr)
        self.assertFalse(os.path.exists(ss.shard_path(self.out_dir, 0)))


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--gesweep", required=True)
    args, rest = parser.parse_known_args()
    GESWEEP = os.path.abspath(args.gesweep)
    unittest.main(argv=[sys.argv[0], *rest], verbosity=2)
