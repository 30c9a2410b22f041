#!/usr/bin/python3
"""The committed results/ against its index and its READMEs (tools/rtlab_report/results_index.py): every
folder under results/ must be named in results/README.md, and every commit a README in
results/ quotes must be recorded by its data (rows, sweep metadata, the tools' logs, or data it
links to), so that a README cannot claim a measurement its folder does not hold.
Standard library only; CTest runs this with /usr/bin/python3.
"""
import json
import os
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RESULTS = os.path.join(ROOT, "results")
sys.path.insert(0, os.path.join(ROOT, "tools"))
from rtlab_report import results_index  # noqa: E402

# Commits these READMEs name that no data under them records. None is a measurement's own
# commit: each is a kernel tree run under another commit's binary (--kernel-dir or
# RTLAB_KERNEL_DIR, which the rows do not record), or code history named for context (the fix,
# the change measured). Listed so that any new unrecorded quote fails; an entry whose commit
# becomes recorded fails too, and must then leave the list.
NOT_IN_DATA = {
    # Generated limits text: a planner bug fixed at ed93f1e, code history.
    ("nvidia-h200/README.md", "ed93f1e"),
    # The compiler hang's range and fix, code history.
    ("nvidia-h200/cornell-196a299/README.md", "1cdc2f1"),
    ("nvidia-h200/cornell-196a299/README.md", "eb664a7"),
    ("nvidia-h200/cornell-196a299/README.md", "7751dbf"),
    # Kernel trees run under the eb664a7 binary; the log names them only in run labels.
    ("nvidia-h200/hang-bisect-eb664a7/README.md", "02b8077"),
    ("nvidia-h200/hang-bisect-eb664a7/README.md", "cb985e5"),
    ("nvidia-h200/hang-bisect-eb664a7/README.md", "1cdc2f1"),
    ("nvidia-h200/hang-bisect-eb664a7/README.md", "7751dbf"),
    # Kernel trees of earlier commits run under the 2f20b57 binary.
    ("nvidia-h200/trace-peer/2f20b57/README.md", "7e39e5b"),
    ("nvidia-h200/trace-peer/2f20b57/README.md", "1a75d90"),
    ("nvidia-h200/trace-peer/2f20b57/README.md", "f300cec"),
    # Traversal changes named as history, and session variants run as kernel trees.
    ("nvidia-h200/trace-peer/65ee11e/README.md", "43d8804"),
    ("nvidia-h200/trace-peer/65ee11e/README.md", "05190d1"),
    ("nvidia-h200/trace-peer/65ee11e/experiments/README.md", "20a2139"),
    ("nvidia-h200/trace-peer/65ee11e/experiments/README.md", "05190d1"),
    # k-base is d0b4c82's kernel tree under the 65ee11e binary; 1e9d134 the kernel committed after.
    ("nvidia-h200/wave-ab/README.md", "d0b4c82"),
    ("nvidia-h200/wave-ab/README.md", "1e9d134"),
    # perf-check's reports record no commit.
    ("pocl-pthread-skylake-avx512-amd-epyc/perf-check/README.md", "9662d72"),
    # The kernels before the change, run under the same binary.
    ("pocl-pthread-skylake-avx512-amd-epyc/trace-peer/README.md", "c9e8912"),
}


class CommittedResultsTest(unittest.TestCase):
    def test_every_result_folder_is_in_the_index(self):
        missing = results_index.missing_from_index(RESULTS)
        self.assertEqual(missing, [], "results/README.md leaves these folders out; run "
                         "python3 -m rtlab_report readme results")

    def test_every_quoted_commit_is_in_the_data(self):
        found = set(results_index.readme_problems(RESULTS))
        self.assertEqual(sorted(found - NOT_IN_DATA), [],
                         "these READMEs quote commits no data under them records")
        self.assertEqual(sorted(NOT_IN_DATA - found), [],
                         "now recorded by the data: take these out of NOT_IN_DATA")


class CheckerTest(unittest.TestCase):
    """The checker itself, on a made-up results folder: it must catch what it is for."""

    def make(self, tmp, readme, rows_commit="8380cd2fad99"):
        folder = os.path.join(tmp, "dev", "set-a")
        os.makedirs(os.path.join(folder, "run-1"))
        with open(os.path.join(folder, "run-1", "rows.jsonl"), "w") as f:
            f.write(json.dumps({"commit": rows_commit, "device_ms": 1.0}) + "\n")
        with open(os.path.join(folder, "README.md"), "w") as f:
            f.write(readme)
        return folder

    def test_a_quote_must_be_a_prefix_of_a_recorded_commit(self):
        with tempfile.TemporaryDirectory() as tmp:
            self.make(tmp, "# Set A at commit 8380cd2\n\nAgainst `b05cbeb` and `1796011267`.\n")
            self.assertEqual(results_index.readme_problems(tmp),
                             [(os.path.join("dev", "set-a", "README.md"), "b05cbeb")])

    def test_a_linked_folder_s_data_backs_a_quote(self):
        with tempfile.TemporaryDirectory() as tmp:
            self.make(tmp, "Same as `b05cbeb` ([set B](../set-b/README.md)).\n")
            other = os.path.join(tmp, "dev", "set-b")
            os.makedirs(other)
            with open(os.path.join(other, "log.txt"), "w") as f:
                f.write("sweep x: 4 cells on Dev, commit b05cbebd3c57\n")
            self.assertEqual(results_index.readme_problems(tmp), [])

    def test_a_folder_missing_from_the_index_is_named(self):
        with tempfile.TemporaryDirectory() as tmp:
            self.make(tmp, "# A\n")
            with open(os.path.join(tmp, "README.md"), "w") as f:
                f.write("- [`dev`](dev/README.md)\n- [`dev/set-a`](dev/set-a/README.md)\n")
            self.assertEqual(results_index.missing_from_index(tmp), ["dev/set-a/run-1"])


if __name__ == "__main__":
    unittest.main()
