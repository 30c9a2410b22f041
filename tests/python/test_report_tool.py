#!/usr/bin/python3
"""tools/rtlab_report as one tool: its one entry point lists and runs every command, each
command's module loads, the scene generators stay standard-library scripts of their own, and
the predictor is scored at the threshold rtlab ships. CTest runs this with /usr/bin/python3.
"""
import ast
import importlib
import os
import subprocess
import sys
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOOL = os.path.join(ROOT, "tools", "rtlab_report")
sys.path.insert(0, os.path.join(ROOT, "tools"))
from rtlab_report import cli, predict_eval  # noqa: E402

try:
    import matplotlib  # noqa: F401
    HAVE_MPL = True
except ImportError:
    HAVE_MPL = False


class EntryPointTest(unittest.TestCase):
    def run_tool(self, *args, module=False):
        cmd = [sys.executable, "-m", "rtlab_report"] if module else [sys.executable, TOOL]
        env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "tools"))
        return subprocess.run(cmd + list(args), capture_output=True, text=True, env=env)

    def test_help_lists_every_command_both_ways(self):
        for module in (False, True):
            done = self.run_tool("help", module=module)
            self.assertEqual(done.returncode, 0, done.stderr)
            for name in cli.COMMANDS:
                self.assertIn(name, done.stdout)

    def test_an_unknown_command_is_one_line_and_status_2(self):
        done = self.run_tool("chart")
        self.assertEqual(done.returncode, 2)
        self.assertIn("no command 'chart'", done.stderr)
        self.assertNotIn("Traceback", done.stderr)

    def test_every_command_s_module_has_a_main(self):
        for name, (module, _) in cli.COMMANDS.items():
            if not HAVE_MPL and module.startswith("charts"):
                continue
            mod = importlib.import_module(f"rtlab_report.{module}")
            self.assertTrue(callable(getattr(mod, "main", None)), name)

    def test_check_results_passes_on_the_committed_tree(self):
        done = self.run_tool("check-results", ROOT)
        self.assertEqual(done.returncode, 0, done.stdout)


class ScriptsStayScriptsTest(unittest.TestCase):
    """scripts/ keeps the shell steps and the scene generators, which travel to GPU hosts
    alone (scripts/gpu-sweep.sh prepare): standard library only, no import of the package."""

    def test_scene_generators_import_only_the_standard_library(self):
        for name in ("make-map.py", "make-stress.py"):
            with open(os.path.join(ROOT, "scripts", name)) as f:
                tree = ast.parse(f.read())
            imported = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import)
                        for a in n.names}
            imported |= {n.module.split(".")[0] for n in ast.walk(tree)
                         if isinstance(n, ast.ImportFrom) and n.module}
            self.assertFalse(imported & {"rtlab_report", "matplotlib", "numpy"}, name)
            self.assertTrue(imported <= set(sys.stdlib_module_names), (name, imported))

    def test_no_report_module_is_left_in_scripts(self):
        left = [n for n in os.listdir(os.path.join(ROOT, "scripts"))
                if n.endswith(".py") and not n.startswith("make-")]
        self.assertEqual(left, [])


class ExperimentArchiveTest(unittest.TestCase):
    def test_archive_leaves_out_patches_is_stable_and_gets_a_page(self):
        import tarfile
        import tempfile
        from rtlab_report import experiments, results_check
        with tempfile.TemporaryDirectory() as src, tempfile.TemporaryDirectory() as into:
            exp = os.path.join(src, "dev", "exp-1")
            os.makedirs(exp)
            with open(os.path.join(exp, "README.md"), "w") as f:
                f.write("# Is A faster than B?\n\nOne GPU at `8380cd2`.\n\n"
                        "**A is 1.5x faster.**\n")
            with open(os.path.join(exp, "rows.jsonl"), "w") as f:
                f.write('{"commit": "8380cd2fad99"}\n')
            open(os.path.join(exp, "kernels.patch"), "w").close()
            self.assertEqual(experiments.main([src, "exp-1", "dev/exp-1", "--into", into]), None)
            archive = os.path.join(into, "archive", "exp-1.tar.xz")
            with open(archive, "rb") as f:
                first = f.read()
            experiments.main([src, "exp-1", "dev/exp-1", "--into", into])
            with open(archive, "rb") as f:
                self.assertEqual(f.read(), first)  # re-archiving churns nothing
            with tarfile.open(archive) as tar:
                self.assertEqual(tar.getnames(), ["dev/exp-1/README.md", "dev/exp-1/rows.jsonl"])
            with open(os.path.join(into, "experiments", "exp-1.md")) as f:
                text = f.read()
            self.assertTrue(text.startswith("# Is A faster than B?\n"))
            self.assertIn("- **Commits in the data**: `8380cd2`.", text)
            self.assertIn("**A is 1.5x faster.**", text)
            self.assertEqual(results_check.page_problems(into), [])


class ShippedThresholdTest(unittest.TestCase):
    def test_the_rule_scored_is_the_one_auto_thresholds_h_ships(self):
        with open(os.path.join(ROOT, "auto", "thresholds.h")) as f:
            self.assertIn(f"kGpuThresholds{{{predict_eval.shipped_threshold()}", f.read())


if __name__ == "__main__":
    unittest.main()
