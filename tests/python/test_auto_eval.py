#!/usr/bin/env python3
"""tools/rtlab_report/auto_eval.py: auto within 5% of the better of mega and queue, ties and wins beyond the
frame spread, on rows made to the point."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
from rtlab_report import auto_eval  # noqa: E402


def row(scene, pipeline, ms, spread=0.01, layout=None, design=None, choice=None):
    r = {"scene": scene, "pipeline": pipeline, "status": "ok", "device_ms": ms,
         "device_ms_min": ms - spread / 2, "device_ms_max": ms + spread / 2, "commit": "abc"}
    if layout:
        r["options"] = {"layout": layout}
    if choice:
        r["options"] = {"auto-choice": choice}
    if design:
        r["extras"] = {"auto_design": design, "auto_busy_lanes": 20.0}
    return r


class AutoEval(unittest.TestCase):
    def cells(self, rows):
        out = {}
        for r in rows:
            out.setdefault(r["scene"], {})[auto_eval.design(r)] = r
        return out

    def test_within_over_and_faster(self):
        rows = [
            # 4% over the queue: within the bar.
            row("a", "mega", 2.0, layout="weighted"), row("a", "queue", 1.0),
            row("a", "auto", 1.04, design="queue"),
            # 10% over, beyond the spread: a miss.
            row("b", "mega", 1.0, layout="tree"), row("b", "queue", 3.0),
            row("b", "auto", 1.10, design="wave"),
            # 10% over but inside a wide spread: a tie, so within.
            row("c", "mega", 1.0, spread=0.3, layout="weighted"), row("c", "queue", 3.0),
            row("c", "auto", 1.10, design="wave"),
            # Faster than both beyond the spread.
            row("d", "mega", 1.0, layout="weighted"), row("d", "queue", 1.2),
            row("d", "auto", 0.8, design="wave"),
            # No queue row: not scored.
            row("e", "mega", 1.0, layout="weighted"), row("e", "auto", 1.0, design="mega"),
        ]
        got = {s: (round(ratio, 3), within, faster)
               for s, _, _, _, ratio, within, faster in auto_eval.evaluate(self.cells(rows))}
        self.assertEqual(got, {"a": (1.04, True, False), "b": (1.1, False, False),
                               "c": (1.1, True, False), "d": (0.8, True, True)})
        text = auto_eval.table(auto_eval.evaluate(self.cells(rows)))
        self.assertIn("on 3 of 4 scenes; faster than both beyond the spread on 1", text)
        self.assertIn("Over 5%: `b`", text)

    def test_the_best_of_every_design_is_the_second_baseline(self):
        # Auto within 5% of mega and queue, but the persistent megakernel is 1.5x faster still:
        # against every design it is over 5%, and the table says so.
        rows = [row("a", "mega", 2.0, layout="weighted"), row("a", "queue", 2.1),
                row("a", "persist", 1.0), row("a", "auto", 2.0, design="mega")]
        (_, d, a, _, ratio, within, _), = auto_eval.evaluate(self.cells(rows))
        self.assertEqual((ratio, within), (1.0, True))
        best, ratio_all, within_all = auto_eval.against_every_design(d, a)
        self.assertEqual((best["pipeline"], ratio_all, within_all), ("persist", 2.0, False))
        text = auto_eval.table(auto_eval.evaluate(self.cells(rows)))
        self.assertIn("within 5% or tied on 0 of 1 scenes, worst ratio 2.000", text)
        self.assertIn("leave out its decision", text)

    def test_the_better_megakernel_layout_is_the_bar(self):
        rows = [row("a", "mega", 2.0, layout="tree"), row("a", "mega", 1.0, layout="weighted"),
                row("a", "queue", 3.0), row("a", "auto", 1.5, design="wave")]
        (_, _, _, best, ratio, within, _), = auto_eval.evaluate(self.cells(rows))
        self.assertEqual(best["options"]["layout"], "weighted")
        self.assertAlmostEqual(ratio, 1.5)
        self.assertFalse(within)

    def test_auto_by_prediction_and_by_trial_frames_are_scored_apart(self):
        # One sweep runs auto both ways (bench/sweeps/auto); the trial-frame rows come last and
        # must not stand in for the predicted ones.
        rows = [row("a", "mega", 1.0, layout="weighted"), row("a", "queue", 2.0),
                row("a", "auto", 1.5, design="queue", choice="predict"),
                row("a", "auto", 1.0, design="mega-weighted", choice="measure")]
        cells = self.cells(rows)
        self.assertEqual(sorted(cells["a"]), ["auto", "auto-measure", "mega-weighted", "queue"])
        (_, _, _, _, predicted, within, _), = auto_eval.evaluate(cells)
        self.assertAlmostEqual(predicted, 1.5)
        self.assertFalse(within)
        (_, _, _, _, measured, within, _), = auto_eval.evaluate(cells, "auto-measure")
        self.assertAlmostEqual(measured, 1.0)
        self.assertTrue(within)
        self.assertIn("by trial frames", auto_eval.table(auto_eval.evaluate(cells, "auto-measure"),
                                                          "auto-measure"))


if __name__ == "__main__":
    unittest.main()
