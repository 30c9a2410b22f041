#!/usr/bin/python3
"""Tests of scripts/perf-check's verdicts: the exact signed-rank test, Holm's correction, and that
a check fails when the new build is slower in nearly every round, not when a few runs were slow.
Measurements here are made up; nothing is built or timed."""
import importlib.machinery
import importlib.util
import math
import os
import random
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
_loader = importlib.machinery.SourceFileLoader("perf_check", os.path.join(ROOT, "scripts",
                                                                          "perf-check"))
_spec = importlib.util.spec_from_loader("perf_check", _loader)
perf = importlib.util.module_from_spec(_spec)
_loader.exec_module(perf)

ROUNDS = 12
SCENES = ("cornell", "shadows", "spheres")


def key(scene, pipe):
    return (scene, pipe, "tree", 160, 90, 4, 1, 1, "-")


def measure(slowdown, noise, spikes=(), seed=1, second=1.0):
    """Times of three cells of two pipelines over ROUNDS rounds: `noise` the log-normal spread of
    one run, `slowdown` {pipeline: factor} of the new build, `spikes` the rounds in which the
    new build's run was slowed by a shared load (all its cells alike, by half), and `second` the
    factor by which the second run of a round is slower (round i runs base first when i is
    even, as perf-check does)."""
    rng = random.Random(seed)
    times = {"base": {}, "new": {}}
    for scene in SCENES:
        for pipe in ("mega", "wave"):
            k = key(scene, pipe)
            times["base"][k] = [40 * math.exp(rng.gauss(0, noise)) * (second if i % 2 else 1)
                                for i in range(ROUNDS)]
            times["new"][k] = [40 * slowdown.get(pipe, 1) * math.exp(rng.gauss(0, noise))
                               * (1.5 if i in spikes else 1) * (1 if i % 2 else second)
                               for i in range(ROUNDS)]
    return times


def verdicts(times):
    checks, _, _ = perf.judge(times, ROUNDS)
    return {c["name"]: c for c in checks}


class SignedRankTest(unittest.TestCase):
    def test_exact_values(self):
        self.assertAlmostEqual(perf.signed_rank_p([0.1] * 9), 1 / 512)
        # ranks 1, 2, 3 with the smallest negative: rank sums 5 and 6 of the 8 patterns reach 5
        self.assertAlmostEqual(perf.signed_rank_p([-0.1, 0.2, 0.3]), 2 / 8)
        self.assertAlmostEqual(perf.signed_rank_p([-0.1, -0.2, -0.3]), 1.0)
        # three tied magnitudes share rank 2; two or three positives reach the observed 4
        self.assertAlmostEqual(perf.signed_rank_p([0.1, 0.1, -0.1]), 4 / 8)
        self.assertEqual(perf.signed_rank_p([0.0, 0.0]), 1.0)

    def test_holm(self):
        adjusted = perf.holm([0.01, 0.04, 0.03])
        for got, want in zip(adjusted, [0.03, 0.06, 0.06]):
            self.assertAlmostEqual(got, want)


class JudgeTest(unittest.TestCase):
    def test_equal_builds_pass(self):
        for seed in range(20):
            for c in verdicts(measure({}, 0.15, seed=seed)).values():
                self.assertTrue(c["ok"], (seed, c["name"], c["verdict"]))

    def test_a_few_slow_runs_of_the_new_build_are_a_tie(self):
        # The new build's runs of the first six rounds slowed by about half: every change moves
        # past its tolerance, but in the other six rounds the new build is as often faster as
        # slower. Signed ranks: the six largest (57) plus ranks 1 and 4 (the 1.01 and 1.02
        # rounds) make 62 of 78; 158 of the 4,096 sign patterns reach it, and Holm's correction
        # over the eight checks leaves each at 8 x 158/4096 = 0.31.
        factors = [1.45, 1.5, 1.55, 1.6, 1.65, 1.7, 0.985, 0.99, 1.01, 0.97, 1.02, 0.98]
        times = {"base": {}, "new": {}}
        for i, scene in enumerate(SCENES):
            for pipe in ("mega", "wave"):
                times["base"][key(scene, pipe)] = [40.0 + i] * ROUNDS
                times["new"][key(scene, pipe)] = [(40.0 + i) * f for f in factors]
        v = verdicts(times)
        self.assertEqual(len(v), 8)
        for c in v.values():
            self.assertGreater(c["change"], 1 + c["tolerance"], c["name"])
            self.assertEqual(c["slower_rounds"], 8)
            self.assertAlmostEqual(c["p"], 8 * 158 / 4096)
            self.assertTrue(c["ok"])
            self.assertEqual(c["verdict"], "tie: slower in only 8/12 rounds")

    def test_a_slower_second_run_is_not_a_slowdown(self):
        # Each build runs second in half the rounds, and each pair of rounds cancels the penalty.
        for seed in range(10):
            v = verdicts(measure({}, 0.02, seed=seed, second=1.3))
            for c in v.values():
                self.assertTrue(c["ok"], (seed, c["name"], c["verdict"]))
                self.assertAlmostEqual(c["change"], 1.0, delta=0.05)

    def test_a_slowdown_under_a_second_run_penalty_still_fails(self):
        v = verdicts(measure({"wave": 1.4}, 0.02, second=1.15))
        self.assertFalse(v["wave"]["ok"])
        self.assertAlmostEqual(v["wave"]["change"], 1.4, delta=0.05)
        self.assertTrue(v["mega"]["ok"])

    def test_a_consistent_slowdown_fails_its_pipeline_and_cells(self):
        v = verdicts(measure({"wave": 1.3}, 0.03))
        self.assertFalse(v["wave"]["ok"])
        self.assertAlmostEqual(v["wave"]["change"], 1.3, delta=0.05)
        self.assertEqual(v["wave"]["slower_rounds"], ROUNDS)
        self.assertFalse(v["cornell 160x90 B4 wave"]["ok"])
        self.assertTrue(v["mega"]["ok"])
        self.assertTrue(v["cornell 160x90 B4 mega"]["ok"])

    def test_a_slowdown_inside_the_floor_passes(self):
        v = verdicts(measure({"wave": 1.03}, 0.005))
        self.assertEqual(v["wave"]["slower_rounds"], ROUNDS)
        self.assertTrue(v["wave"]["ok"])

    def test_a_faster_build_passes(self):
        v = verdicts(measure({"mega": 0.6}, 0.03))
        self.assertTrue(v["mega"]["ok"])
        self.assertEqual(v["mega"]["verdict"], "ok (faster)")

    def test_a_cell_missing_from_a_round_is_not_compared(self):
        times = measure({}, 0.03)
        times["new"][key("cornell", "wave")].pop()
        checks, cells, skipped = perf.judge(times, ROUNDS)
        self.assertEqual([k for k, _, _ in skipped], [key("cornell", "wave")])
        self.assertNotIn("cornell 160x90 B4 wave", [c["name"] for c in checks])


if __name__ == "__main__":
    unittest.main()
