#!/usr/bin/python3
"""Tests of scripts/gpu-batch (carried to a GPU host as batch.sh): with stand-ins for the smoke
check and run.sh in a temporary carry folder, every step runs under the limit it was given, the
steps' output comes back as one batch.tar that is rewritten after every step (so a session cut
short keeps what finished), a failing or unknown step makes the exit status 1 without stopping
the others, a tar past 15 MiB is split into parts that join back into it, and a batch deadline
cuts the step limits to fit inside it or skips a step that cannot.
"""
import math
import os
import re
import shutil
import subprocess
import tarfile
import tempfile
import time
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BATCH = os.path.join(ROOT, "scripts", "gpu-batch")

# run.sh's stand-in: what the real one writes (rows, log), the sweep and limit it was asked for,
# and a failure for the sweep named "broken"; BIG_BYTES of incompressible data if set.
RUN_SH = """#!/usr/bin/env bash
mkdir -p "$OUT"
echo "{\\"status\\": \\"ok\\", \\"sweep\\": \\"$RTLAB_SWEEP\\"}" > "$OUT/rows.jsonl"
echo "limit $RTLAB_GPU_TIME_LIMIT gbench $RTLAB_GPU_GBENCH_S" > "$OUT/log.txt"
[ -z "${BIG_BYTES:-}" ] || head -c "$BIG_BYTES" /dev/urandom > "$OUT/images.tar.xz"
[ "$RTLAB_SWEEP" != broken ] || exit 4
"""
SMOKE_SH = """#!/usr/bin/env bash
mkdir -p "$OUT"
echo "gpu-smoke: 3 passed, 0 failed (limit $RTLAB_SMOKE_LIMIT)" | tee "$OUT/smoke.txt"
"""


class GpuBatch(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="rtlab-gpu-batch-")
        self.carry = os.path.join(self.tmp, "carry")
        os.makedirs(os.path.join(self.carry, "sweeps"))
        shutil.copy(BATCH, os.path.join(self.carry, "batch.sh"))
        for name, text in (("run.sh", RUN_SH), ("smoke.sh", SMOKE_SH)):
            with open(os.path.join(self.carry, name), "w") as f:
                f.write(text)
        for sweep in ("alpha", "beta", "broken"):
            open(os.path.join(self.carry, "sweeps", sweep), "w").close()
        self.out = os.path.join(self.tmp, "out")

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def batch(self, *steps, **env):
        return subprocess.run(
            ["bash", os.path.join(self.carry, "batch.sh"), *steps], capture_output=True, text=True,
            env={**os.environ, "OUT": self.out, "RTLAB_BATCH_DIR": os.path.join(self.tmp, "w"),
                 **env})

    def members(self):
        with tarfile.open(os.path.join(self.out, "batch.tar")) as tar:
            return {m.name.lstrip("./"): tar.extractfile(m).read().decode(errors="replace")
                    for m in tar.getmembers() if m.isfile()}

    def test_every_step_comes_back_in_one_tar_with_its_limit(self):
        run = self.batch("smoke:200", "alpha:90", "beta")
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
        self.assertEqual(sorted(os.listdir(self.out)), ["batch.tar", "progress.txt"])
        files = self.members()
        self.assertIn("3 passed, 0 failed (limit 200)", files["smoke/smoke.txt"])
        self.assertIn('"sweep": "alpha"', files["alpha/rows.jsonl"])
        self.assertEqual(files["alpha/log.txt"].strip(), "limit 90 gbench 0")
        self.assertEqual(files["beta/log.txt"].strip(), "limit 480 gbench 0")  # the default
        with open(os.path.join(self.out, "progress.txt")) as f:
            progress = f.read()
        for step in ("smoke", "alpha", "beta"):
            self.assertIn(f"{step}: status 0", progress)

    def test_a_failed_or_unknown_step_fails_the_batch_but_not_the_steps_after_it(self):
        run = self.batch("broken", "nosuch", "alpha")
        self.assertEqual(run.returncode, 1)
        self.assertIn("nosuch: no sweep of that name", run.stdout)
        self.assertIn("broken: status 4", run.stdout)
        files = self.members()
        self.assertIn("broken/rows.jsonl", files)  # what it wrote before failing still comes back
        self.assertIn("alpha/rows.jsonl", files)

    def test_a_large_batch_is_split_into_parts_that_join_back(self):
        run = self.batch("alpha", BIG_BYTES=str(17 * 1024 * 1024))
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
        parts = sorted(p for p in os.listdir(self.out) if p.startswith("batch.tar.part-"))
        self.assertEqual(parts, ["batch.tar.part-aa", "batch.tar.part-ab"])
        self.assertFalse(os.path.exists(os.path.join(self.out, "batch.tar")))
        with open(os.path.join(self.out, "batch.tar"), "wb") as joined:
            for p in parts:
                with open(os.path.join(self.out, p), "rb") as f:
                    joined.write(f.read())
        self.assertIn("alpha/rows.jsonl", self.members())

    def test_a_deadline_cuts_step_limits_to_fit_and_skips_a_step_without_room(self):
        # 300 s for the batch, 45 s of slack a step: smoke keeps its 100 (the stand-ins take no
        # time), alpha's 480 becomes 255, and beta, asked for 400, is still cut to 255: the
        # stand-ins return at once, so each step finds the whole deadline left, less the whole
        # seconds the batch has run by then (a loaded machine may take one or two).
        start = time.monotonic()
        run = self.batch("smoke:100", "alpha", "beta:400", RTLAB_BATCH_DEADLINE="300")
        took = math.ceil(time.monotonic() - start)
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
        files = self.members()
        self.assertIn("(limit 100)", files["smoke/smoke.txt"])
        for step in ("alpha", "beta"):
            m = re.fullmatch(r"limit (\d+) gbench 0", files[f"{step}/log.txt"].strip())
            self.assertIsNotNone(m, files[f"{step}/log.txt"])
            self.assertTrue(255 - took <= int(m.group(1)) <= 255, (step, m.group(1), took))
        self.assertRegex(run.stdout, r"alpha: limit cut from 480 to (\d+) s \(batch deadline\)")
        # A deadline shorter than the slack and 20 s leaves no room: the step is skipped, the
        # batch fails and says why.
        run = self.batch("alpha:60", RTLAB_BATCH_DEADLINE="50")
        self.assertEqual(run.returncode, 1)
        self.assertIn("alpha: skipped", run.stdout)
        self.assertNotIn("alpha/rows.jsonl", self.members())

    def test_a_limit_that_is_not_a_number_is_one_line_and_exit_2(self):
        for steps, env, named in ((["alpha:soon"], {}, "step alpha:"),
                                  (["alpha"], {"RTLAB_BATCH_DEADLINE": "10m"},
                                   "RTLAB_BATCH_DEADLINE '10m'")):
            run = self.batch(*steps, **env)
            self.assertEqual(run.returncode, 2, run.stdout + run.stderr)
            self.assertEqual(len(run.stderr.strip().splitlines()), 1, run.stderr)
            self.assertIn(named, run.stderr)
            self.assertIn("must be a whole number of seconds", run.stderr)
            self.assertFalse(os.path.exists(os.path.join(self.tmp, "w", "alpha")))  # nothing ran

    def test_no_steps_prints_the_usage_and_exits_2(self):
        run = self.batch()
        self.assertEqual(run.returncode, 2)
        self.assertIn("batch.sh [smoke[:SECONDS]] SWEEP[:SECONDS]", run.stdout)


class GpuSweepRun(unittest.TestCase):
    def test_a_prebuild_count_that_is_not_a_number_is_one_line_and_exit_2(self):
        # scripts/gpu-sweep-run.sh, carried as run.sh beside a SWEEP file: it stops before it
        # looks for a device or runs anything.
        with tempfile.TemporaryDirectory(prefix="rtlab-gpu-run-") as tmp:
            shutil.copy(os.path.join(ROOT, "scripts", "gpu-sweep-run.sh"),
                        os.path.join(tmp, "run.sh"))
            with open(os.path.join(tmp, "SWEEP"), "w") as f:
                f.write("alpha\n")
            run = subprocess.run(["bash", os.path.join(tmp, "run.sh")], capture_output=True,
                                 text=True, env={**os.environ, "OUT": os.path.join(tmp, "out"),
                                                 "RTLAB_GPU_PREBUILD": "many"})
            self.assertEqual(run.returncode, 2, run.stdout + run.stderr)
            self.assertEqual(run.stderr.strip(), "run.sh: RTLAB_GPU_PREBUILD 'many': must be a "
                             "whole number of processes")
            self.assertFalse(os.path.exists(os.path.join(tmp, "out", "log.txt")))


if __name__ == "__main__":
    unittest.main()
