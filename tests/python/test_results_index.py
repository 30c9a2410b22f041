#!/usr/bin/python3
"""The committed results/ against its index, its archives and the READMEs that quote it
(tools/rtlab_report/results_check.py): one folder a device kind, one page and one archive an
experiment, every top-level entry and page in results/README.md, no patch files, and every commit
a README quotes recorded by the data it links, so that neither the index nor a README (the
repository's included, whatever its wording) can claim a measurement results/ does not hold.
Standard library only; CTest runs this with /usr/bin/python3.
"""
import json
import os
import sys
import tarfile
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RESULTS = os.path.join(ROOT, "results")
sys.path.insert(0, os.path.join(ROOT, "tools"))
from rtlab_report import results_check, results_index  # noqa: E402

NOT_IN_DATA = results_check.NOT_IN_DATA
README_HISTORY = results_check.README_HISTORY


class CommittedResultsTest(unittest.TestCase):
    def test_the_top_level_is_device_folders_experiments_and_archive(self):
        for entry in results_check.top_entries(RESULTS):
            path = os.path.join(RESULTS, entry)
            self.assertTrue(os.path.isdir(path), f"results/{entry} is a loose file")
            if entry not in ("experiments", "archive"):
                self.assertTrue(os.path.exists(os.path.join(path, "README.md")),
                                f"results/{entry} has no README")
                subs = [d for d in os.listdir(path) if os.path.isdir(os.path.join(path, d))]
                self.assertEqual(subs, [], f"results/{entry} holds folders: an experiment's "
                                 "files go to archive/ (python3 -m rtlab_report experiment)")

    def test_each_published_set_is_at_one_commit(self):
        several = {slug for slug, c in results_check.set_commits(RESULTS).items() if len(c) > 1}
        self.assertEqual(sorted(several - results_check.NOT_YET_ONE_COMMIT), [],
                         "a published set must be measured at one commit")
        self.assertEqual(sorted(results_check.NOT_YET_ONE_COMMIT - several), [],
                         "now at one commit: take these out of NOT_YET_ONE_COMMIT")

    def test_index_names_everything_and_every_page_has_its_archive(self):
        self.assertEqual(results_check.index_problems(RESULTS), [],
                         "run /usr/bin/python3 tools/rtlab_report readme results")

    def test_every_page_s_commits_are_in_its_archive(self):
        self.assertEqual(results_check.page_problems(RESULTS), [])

    def test_every_commit_a_results_readme_quotes_is_in_its_data(self):
        found = set(results_index.readme_problems(RESULTS))
        self.assertEqual(sorted(found - NOT_IN_DATA), [],
                         "these READMEs quote commits no data under them records")
        self.assertEqual(sorted(NOT_IN_DATA - found), [],
                         "now recorded by the data: take these out of NOT_IN_DATA")

    def test_every_commit_the_readme_quotes_is_in_the_data_it_links(self):
        found = results_check.readme_quote_problems(os.path.join(ROOT, "README.md"), RESULTS)
        self.assertEqual([(c, where) for c, where in found if c not in README_HISTORY], [],
                         "README.md quotes these commits beside links into results/ whose "
                         "data does not record them")


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


class LayoutCheckerTest(unittest.TestCase):
    """The index and README checks on a made-up results/: each catches what it is for."""

    def make(self, tmp, index, readme, page_commit="8380cd2"):
        results = os.path.join(tmp, "results")
        for d in ("dev", "experiments", "archive"):
            os.makedirs(os.path.join(results, d))
        with open(os.path.join(results, "dev", "README.md"), "w") as f:
            f.write("# Dev\n")
        with open(os.path.join(results, "dev", "full.json"), "w") as f:
            json.dump({"meta": {"commit": "5af2c8e0"}, "rows": []}, f)
        rows = os.path.join(tmp, "rows.jsonl")
        with open(rows, "w") as f:
            f.write(json.dumps({"commit": "8380cd2fad99"}) + "\n")
        with tarfile.open(os.path.join(results, "archive", "exp.tar.xz"), "w:xz") as tar:
            tar.add(rows, "dev/exp/rows.jsonl")
        with open(os.path.join(results, "experiments", "exp.md"), "w") as f:
            f.write(f"# Exp\n\n- **Commits in the data**: `{page_commit}`.\n"
                    "- **Raw data**: [`archive/exp.tar.xz`](../archive/exp.tar.xz).\n")
        with open(os.path.join(results, "README.md"), "w") as f:
            f.write(index)
        with open(os.path.join(tmp, "README.md"), "w") as f:
            f.write(readme)
        return results

    FULL_INDEX = "[`dev`](dev/README.md) [`experiments/`](experiments/) [`archive/`](archive/) " \
                 "[Exp](experiments/exp.md)\n"

    def test_a_complete_index_passes_and_a_missing_entry_is_named(self):
        with tempfile.TemporaryDirectory() as tmp:
            results = self.make(tmp, self.FULL_INDEX, "")
            self.assertEqual(results_check.index_problems(results), [])
            self.assertEqual(results_check.page_problems(results), [])
            results = self.make(os.path.join(tmp, "b"), "[`dev`](dev/README.md)\n", "",
                                page_commit="b05cbeb")
            self.assertEqual(len(results_check.index_problems(results)), 3)
            self.assertEqual(results_check.page_problems(results),
                             ["experiments/exp.md lists b05cbeb, not in its archive's data"])

    def test_a_patch_file_fails_anywhere(self):
        with tempfile.TemporaryDirectory() as tmp:
            results = self.make(tmp, self.FULL_INDEX, "")
            open(os.path.join(results, "dev", "kernels.patch"), "w").close()
            self.assertEqual(results_check.index_problems(results),
                             ["patch file dev/kernels.patch"])

    def test_readme_quotes_are_held_to_the_data_their_block_links(self):
        with tempfile.TemporaryDirectory() as tmp:
            readme = ("The verdict at `5af2c8e` ([set](results/dev/README.md)).\n\n"
                      "- The map at commit 8380cd2 ([page](results/experiments/exp.md#x)).\n"
                      "- Also at `b05cbeb` ([set](results/dev/full.json)).\n\n"
                      "The fix came at `8380cd2`, no link here.\n\n"
                      "A block without links quoting `abc1234` fails.\n")
            results = self.make(tmp, self.FULL_INDEX, readme)
            found = results_check.readme_quote_problems(os.path.join(tmp, "README.md"), results)
            self.assertEqual([c for c, _ in found], ["b05cbeb", "abc1234"])


if __name__ == "__main__":
    unittest.main()
