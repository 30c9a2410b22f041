#!/usr/bin/python3
"""Tests of the result charts and READMEs (rtlab_report/charts.py, results_readme.py, sweep_rows.py):
what a reader sees — one legend entry per visible line, labels that do not overlap, log axes
labelled in one style, no placeholder PNG — and that pipelines, titles and failure kinds come
from the rows, so that a third pipeline needs no code. CTest runs this with /usr/bin/python3
(Debian's matplotlib); the chart tests are skipped where matplotlib is missing.
Every test writes into a temporary folder of its own.
"""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The package's entry point, run as a command; its modules imported from tools/.
TOOL = os.path.join(ROOT, "tools", "rtlab_report")
sys.path.insert(0, os.path.join(ROOT, "tools"))
from rtlab_report import sweep_rows  # noqa: E402

try:
    from rtlab_report import charts  # noqa: E402
    from rtlab_report import chart_style  # noqa: E402
    HAVE_MPL = True
except ImportError:
    HAVE_MPL = False

META = {"device": "Test device", "platform": "Test", "driver": "1", "commit": "abc", "sweep": "t",
        "settings": {"repeats": 3, "warmup": 1}, "max_alloc_bytes": 2**30}
PIPES = [("mega", "megakernel", "tree"), ("mega", "megakernel", "weighted"),
         ("wave", "wavefront", "tree"), ("queue", "queue wavefront", "tree")]


def row(pipe, title, layout, scene, b, w=320, h=180, group="bounces", **extra):
    r = {"pipeline": pipe, "pipeline_title": title, "layout": layout, "scene": scene,
         "width": w, "height": h, "bounces": b, "shadow_samples": 1, "aa": 1, "accel": "-",
         "adaptive": False, "memory_budget": 0, "groups": [group], "status": "ok", "failure": "",
         "error": "", "device_ms": (1 + b) * (1 + len(pipe)) * (1.5 if layout == "weighted" else 1),
         "device_bytes": 2**20 * (1 + b * (pipe != "mega")), "private_bytes": 64 * (1 + b),
         "kernel_ms": {f"{pipe}_a": 0.5 + b, f"{pipe}_b": 0.2}, "tree_nodes": 2**(b + 1) - 1,
         "tree_bytes": 0, "memory_tiles": 1, "scene_info": {"objects": 2, "spheres": 2,
                                                            "triangles": 0}}
    r.update(extra)
    return r


def sweep_rows_fixture(groups=("bounces", "resolution")):
    rows = []
    for pipe, title, layout in PIPES:
        for scene in ("spheres", "cornell"):
            if "bounces" in groups:
                rows += [row(pipe, title, layout, scene, b) for b in range(5)]
            if "resolution" in groups:
                rows += [row(pipe, title, layout, scene, 2, w, h, "resolution")
                         for w, h in ((320, 180), (640, 360), (1280, 720))]
    return rows


def write_rows(d, name, rows):
    """rows as JSON lines in d/name; the path."""
    path = os.path.join(d, name)
    with open(path, "w") as f:
        f.write("\n".join(json.dumps(r) for r in rows) + "\n")
    return path


def run_chart(command, rows, sweep, *args, d=None):
    """rows.jsonl and a sweep.json of sweep `sweep` in d (a new folder unless given), and
    `python3 tools/rtlab_report command` run on them with args: (d, the finished process)."""
    d = d or tempfile.mkdtemp()
    path = write_rows(d, "rows.jsonl", rows)
    with open(os.path.join(d, "sweep.json"), "w") as f:
        json.dump(dict(META, sweep=sweep), f)
    return d, subprocess.run([sys.executable, TOOL, command, path, *args],
                             capture_output=True, text=True)


def load_script(name):
    """A module of the package by its name."""
    return importlib.import_module("rtlab_report." + name)


def crossover_fixture():
    """Rows of a tiny crossover sweep: the queue's ratio falls with the octaves and crosses 1
    between K = 2 and K = 4 (1.5, 1.2, 0.8 by construction); the tree wavefront never does."""
    rows = []
    for m in (1, 4):
        for k, q in ((0, 1.5), (2, 1.2), (4, 0.8)):
            scene = f"divergence-o{k}-m{m}"
            for pipe, layout, ms in (("mega", "tree", 10.0), ("mega", "weighted", 12.0),
                                     ("wave", "tree", 30.0), ("queue", "weighted", 10.0 * q)):
                rows.append(row(pipe, pipe, layout, scene, 4, group="crossover", device_ms=ms,
                                kernel_resources={"Megakernel_Render.registers": 122,
                                                  "Megakernel_Render.private_bytes": 0}))
    return rows


class CrossoverTest(unittest.TestCase):
    def test_crossing_is_the_first_win_beyond_the_spread_never_interpolated(self):
        from rtlab_report import readme_crossover as rc
        mega = {"device_ms": 10.0, "device_ms_min": 9.9, "device_ms_max": 10.1}

        def point(k, ms, lo, hi):
            return (k, ms / 10.0, {"device_ms": ms, "device_ms_min": lo, "device_ms_max": hi}, mega)
        # K=2 is under 1 but within the queue's own spread (9.7 vs 10, spread 0.6): a tie, not
        # a crossover; K=4 wins beyond it. Nothing is interpolated between the two.
        pts = [point(0, 15.0, 14.9, 15.1), point(2, 9.7, 9.4, 10.0), point(4, 8.0, 7.9, 8.1)]
        self.assertEqual([rc.outcome(p) for p in pts], ["loss", "tie", "win"])
        self.assertEqual(rc.crossing(pts), 4)
        self.assertEqual(rc.crossing([point(0, 9.0, 8.9, 9.1)]), 0)
        # Two identical medians are a tie even with no spread recorded.
        same = (8, 1.0, {"device_ms": 10.0}, {"device_ms": 10.0})
        self.assertEqual(rc.outcome(same), "tie")
        self.assertIsNone(rc.crossing([point(0, 20.0, 19, 21), same]))

    def test_section_states_the_crossover_and_the_registers(self):
        from rtlab_report import readme_crossover
        doc = "\n".join(readme_crossover.crossover_section(
            {"meta": META, "rows": crossover_fixture()}, "x.json", False))
        # The fixture's rows carry no frame spread: only equal medians tie, so the queue's 0.8
        # at K = 4 is its first win.
        self.assertIn("M=1 320×180 B=4: first wins at K=4", doc)
        self.assertIn("in 2 of 6 settings, tied in 0, slower in 4", doc)
        self.assertIn("No crossover up to the largest cost tried (K = 4", doc)
        self.assertIn("| 122 |", doc)

    @unittest.skipUnless(HAVE_MPL, "needs matplotlib")
    def test_chart_has_a_panel_per_material_count(self):
        from rtlab_report import charts_crossover
        fig = charts_crossover.crossover_chart(META, crossover_fixture())
        titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
        self.assertEqual(titles, ["1 distinct material", "4 distinct materials"])
        self.assertIsNone(charts_crossover.crossover_chart(META, sweep_rows_fixture()))
        chart_style.plt.close("all")


class RowsTest(unittest.TestCase):
    def test_series_come_from_the_rows(self):
        series = sweep_rows.Series(sweep_rows_fixture())
        self.assertEqual(series.keys, ["mega/tree", "mega/weighted", "queue", "wave"])
        self.assertEqual(series.label("queue"), "queue wavefront")
        self.assertEqual(series.label("mega/weighted"), "megakernel (weighted)")

    def test_a_new_pipelines_family_and_options_need_no_script_change(self):
        # Rows of today carry the pipeline's family and its own options: a design the scripts
        # have never heard of is compared as its family says, and split by its own option.
        rows = [dict(row("persist", "persistent megakernel", "tree", "s", 2, device_ms=ms),
                     family="megakernel", options={"batch": batch})
                for batch, ms in ((32, 5.0), (64, 4.0))]
        rows += [dict(row("queue", "queue wavefront", "weighted", "s", 2, device_ms=6.0),
                      family="wavefront", options={"pool": 0})]
        series = sweep_rows.Series(rows)
        self.assertEqual(series.keys, ["persist/batch=32", "persist/batch=64", "queue"])
        self.assertEqual(series.label("persist/batch=64"),
                         "persistent megakernel (batch=64)")
        self.assertEqual([sweep_rows.family(r) for r in rows],
                         ["megakernel", "megakernel", "wavefront"])
        # Rows from before: the megakernel's layout was its one option, every row had one.
        old = row("wave", "wavefront", "weighted", "s", 2)
        self.assertEqual(sweep_rows.own_options(old), {})
        self.assertEqual(sweep_rows.family(old), "wavefront")

    def test_a_series_of_several_options_is_named_by_those_set(self):
        # Two options vary among the rows: each series is named by the options its cells set
        # away from their defaults, in the registry's words, and the all-default one says so.
        def persist(ms, options, labels):
            return dict(row("persist", "persistent megakernel", "tree", "s", 2, device_ms=ms),
                        family="megakernel", options=options, option_labels=labels)
        rows = [persist(5.0, {"loop": "flat", "lanes": 0}, {}),
                persist(4.0, {"loop": "nested", "lanes": 0}, {"loop": "nested loop"}),
                persist(3.0, {"loop": "flat", "lanes": 256}, {"lanes": "256 lanes a group"})]
        series = sweep_rows.Series(rows)
        self.assertEqual([series.label(k) for k in series.keys],
                         ["persistent megakernel (defaults)",
                          "persistent megakernel (256 lanes a group)",
                          "persistent megakernel (nested loop)"])

    @unittest.skipUnless(HAVE_MPL, "needs matplotlib")
    def test_series_of_one_pipeline_get_fills_of_their_own(self):
        # A map fills cells, where line styles cannot tell one pipeline's schedules apart: the
        # first keeps the palette colour, the others are shades of it, every fill distinct.
        rows = [dict(row("persist", "persistent megakernel", "tree", "s", 2, device_ms=ms),
                     family="megakernel", options={"loop": loop, "lanes": lanes})
                for loop, lanes, ms in (("flat", 0, 5.0), ("nested", 0, 4.0), ("flat", 256, 3.0))]
        rows.append(dict(row("queue", "queue wavefront", "weighted", "s", 2), options={}))
        series = sweep_rows.Series(rows)
        fills = [chart_style.series_fill(series, k) for k in series.keys]
        self.assertEqual(len(set(fills)), 4, fills)
        self.assertEqual(fills[0].lower(), "#56b4e9")  # the persistent megakernel's own
        self.assertEqual(fills[3].lower(), "#cc79a7")  # the queue's, unshaded
        self.assertEqual(chart_style.text_on("#dddddd"), "black")
        self.assertEqual(chart_style.text_on("#0072B2"), "white")

    def test_failure_is_read_from_the_field_not_the_message(self):
        rows = [row("mega", "megakernel", "tree", "s", b, group="limits") for b in range(3)]
        rows[2].update(status="error", failure="opencl", error="tree in private memory")
        (s,) = [s for s in sweep_rows.limit_series(rows) if s["axis"] == "bounces"]
        self.assertEqual(s["how"], "opencl")
        self.assertEqual(sweep_rows.failure({"status": "error"}), "other")

    def test_migration_maps_messages_to_the_fixed_kinds(self):
        migrate = load_script("migrate_rows")
        self.assertEqual(migrate.classify({"status": "ok"}), "")
        self.assertEqual(migrate.classify({"status": "skipped"}), "skipped")
        self.assertEqual(migrate.classify({"status": "error", "failure": "allocation"}),
                         "out_of_memory")
        self.assertEqual(migrate.classify({"status": "error", "error": "x in private memory"}),
                         "private_tree")

    def test_tree_size_says_tile_and_whole(self):
        r = row("wave", "wavefront", "tree", "s", 8, 1280, 720, tree_nodes=511,
                tree_bytes=1280 * 676 * 511 * 48, memory_tiles=2)
        tile, whole, tiles = sweep_rows.tree_sizes(r)
        self.assertEqual(whole, 1280 * 720 * 511 * 48)  # a row from before tree_pixel_bytes
        self.assertEqual((tile < whole, tiles), (True, 2))
        # Newer rows say what a pixel's tree takes (payloads and traced flags).
        r["extras"] = {"tree_pixel_bytes": 511 * 48 + 64}
        self.assertEqual(sweep_rows.tree_sizes(r)[1], 1280 * 720 * (511 * 48 + 64))


class ReadmeTest(unittest.TestCase):
    def write_set(self, tmp):
        folder = os.path.join(tmp, "results", "test-device")
        os.makedirs(folder)
        path = os.path.join(folder, "t.json")
        with open(path, "w") as f:
            json.dump({"meta": META, "rows": sweep_rows_fixture()}, f)
        return path

    def run_readme(self, *args):
        return subprocess.run([sys.executable, TOOL, "readme", *args],
                              capture_output=True, text=True, check=True)

    def test_a_sweep_does_not_rewrite_the_index_unless_asked(self):
        with tempfile.TemporaryDirectory(prefix="rtlab-test-charts-") as tmp:
            path = self.write_set(tmp)
            index = os.path.join(tmp, "results", "README.md")
            self.run_readme(path)
            self.assertTrue(os.path.exists(os.path.join(os.path.dirname(path), "README.md")))
            self.assertFalse(os.path.exists(index))
            self.run_readme(path, "--index")
            self.assertTrue(os.path.exists(index))

    def test_a_file_that_is_not_a_sweep_is_one_line_and_an_error(self):
        with tempfile.TemporaryDirectory(prefix="rtlab-test-charts-") as tmp:
            path = os.path.join(tmp, "not-a-sweep.json")
            with open(path, "w") as f:
                f.write("[1, 2")
            commands = ["readme"] + (["charts"] if HAVE_MPL else [])
            for command in commands:
                done = subprocess.run([sys.executable, TOOL, command, path],
                                      capture_output=True, text=True)
                self.assertNotEqual(done.returncode, 0)
                self.assertIn("not a sweep JSON", done.stderr)
                self.assertNotIn("Traceback", done.stderr)

    def test_a_hand_written_about_file_titles_the_readme_and_survives_regeneration(self):
        with tempfile.TemporaryDirectory(prefix="rtlab-test-charts-") as tmp:
            path = self.write_set(tmp)
            folder = os.path.dirname(path)
            readme = os.path.join(folder, "README.md")
            self.run_readme(path)
            with open(readme) as f:
                plain = f.read()
            self.assertTrue(plain.startswith("# Results: "), plain[:80])
            self.assertNotIn("ABOUT.md", plain)
            with open(os.path.join(folder, "ABOUT.md"), "w") as f:
                f.write("# Results: the rest of a split set\n\nMeasured apart because of X.\n")
            for _ in range(2):  # a second run neither loses nor repeats it
                self.run_readme(path)
                with open(readme) as f:
                    text = f.read()
                self.assertTrue(text.startswith("# Results: the rest of a split set\n"))
                self.assertEqual(text.count("Measured apart because of X."), 1)
                self.assertIn("[`ABOUT.md`](ABOUT.md)", text)
                # The context sits under the header table, before the first section.
                self.assertLess(text.index("| Device |"), text.index("Measured apart"))
                self.assertLess(text.index("Measured apart"), text.index("## Which pipeline"))

    def test_every_pipeline_has_a_column(self):
        with tempfile.TemporaryDirectory(prefix="rtlab-test-charts-") as tmp:
            path = self.write_set(tmp)
            self.run_readme(path)
            with open(os.path.join(os.path.dirname(path), "README.md")) as f:
                text = f.read()
            for title in ("megakernel (tree)", "megakernel (weighted)", "queue wavefront",
                          "wavefront"):
                self.assertIn(f"| {title}: time / fastest", text)

    def test_floor_counts_each_design_s_bytes(self):
        from rtlab_report import readme_floor
        px = 320 * 180
        mega = row("mega", "megakernel", "tree", "s", 3)
        self.assertEqual(readme_floor.floor_bytes(mega), px * 12)  # the image alone
        # The tree wavefront, 2x2 AA, N = 15, rays not counted, a row from before the bit mask:
        # per pixel and sample 15 flag bytes cleared, the primary node written and read (48 B).
        wave = row("wave", "wavefront", "tree", "s", 3, aa=2, tree_nodes=15, tree_bytes=px * 15 * 48)
        self.assertEqual(readme_floor.floor_bytes(wave), px * 12 + 4 * px * (15 + 2 * 48))
        # Counted rays: the traced nodes are the primary, reflection and refraction rays.
        wave["rays"] = {"primary": 4 * px, "reflection": 1000, "refraction": 10, "shadow": 7}
        self.assertEqual(readme_floor.floor_bytes(wave),
                         px * 12 + 4 * px * 15 + (4 * px + 1010) * 2 * 48)
        # The bit mask: a pixel's flags are its tree_pixel_bytes beyond the 15 nodes (one word).
        wave["extras"] = {"tree_pixel_bytes": 15 * 48 + 4}
        self.assertEqual(readme_floor.floor_bytes(wave),
                         px * 12 + 4 * px * 4 + (4 * px + 1010) * 2 * 48)
        # The queue: every extended ray's record (44 B) and hit (48 B), written and read.
        queue = row("queue", "queue wavefront", "tree", "s", 1,
                    extras={"queue_lengths": [[10, 20, 30, 40, 0], [1, 2, 3, 4, 0]]})
        self.assertEqual(readme_floor.floor_bytes(queue), px * 12 + 110 * 2 * 92)
        self.assertIsNone(readme_floor.floor_bytes(row("mega", "m", "tree", "s", 1, status="error")))

    def test_floor_section_only_beside_a_roofline(self):
        with tempfile.TemporaryDirectory(prefix="rtlab-test-charts-") as tmp:
            path = self.write_set(tmp)
            readme = os.path.join(os.path.dirname(path), "README.md")
            self.run_readme(path)
            with open(readme) as f:
                self.assertNotIn("against its floor", f.read())
            with open(os.path.join(os.path.dirname(path), "roofline.json"), "w") as f:
                json.dump({"copy_gb_per_s": 100.0}, f)
            self.run_readme(path)
            with open(readme) as f:
                text = f.read()
            self.assertIn("## Each frame against its floor", text)
            self.assertIn("(100 GB/s, read + write", text)
            # megakernel at 320x180: 691200 B / 100 GB/s = 0.006912 ms; its frame is
            # (1 + b) * 5 ms, so at B = 0 the frame is 5 / 0.006912 = 723.4 floors.
            section = text.split("## Each frame against its floor")[1].split("\n## ")[0]
            line = next(x for x in section.splitlines() if x.startswith("| spheres | 320×180 | 0 | 1 |"))
            self.assertIn("| 0.00691 | 723.4 |", line)


@unittest.skipUnless(HAVE_MPL, "matplotlib is not installed")
class ChartsTest(unittest.TestCase):
    def tearDown(self):
        chart_style.plt.close("all")

    def test_no_placeholder_for_a_sweep_without_accuracy_cells(self):
        with tempfile.TemporaryDirectory(prefix="rtlab-test-charts-") as tmp:
            path = os.path.join(tmp, "t.json")
            with open(path, "w") as f:
                json.dump({"meta": META, "rows": sweep_rows_fixture(("bounces",))}, f)
            subprocess.run([sys.executable, TOOL, "charts", path],
                           capture_output=True, check=True)
            written = sorted(os.listdir(tmp))
        self.assertIn("time-vs-bounces.png", written)
        for name in ("speed-vs-accuracy.png", "time-vs-resolution.png", "limits.png"):
            self.assertNotIn(name, written)

    def test_every_chart_draws_three_pipelines_and_two_layouts(self):
        rows = sweep_rows_fixture()
        for pipe, title, layout in PIPES:
            rows += [row(pipe, title, layout, "spheres", b, group="accuracy", rmse=0.1 / (1 + b),
                         psnr_db=20 + b, reference={"bounces": 8}) for b in range(3)]
            limits = [row(pipe, title, layout, "spheres", b, group="limits") for b in range(4)]
            limits[-1].update(status="error", failure="out_of_memory", device_ms=None)
            rows += limits
        rows += crossover_fixture()
        figs = charts.draw_all(META, rows)
        self.assertTrue(all(figs.values()), [k for k, v in figs.items() if not v])
        self.assertEqual(texts_overlap(figs["limits.png"]), [])

    def test_memory_legend_has_one_entry_per_visible_line(self):
        fig = charts.memory_vs_bounces(META, sweep_rows_fixture())
        fig.canvas.draw()
        panels = [ax for ax in fig.axes if ax.lines]
        legends = fig.axes[-1].artists + [fig.axes[-1].get_legend()]
        entries = sum(len(lg.get_texts()) for lg in legends if lg)
        lines = sum(len(ax.lines) for ax in panels)
        self.assertEqual(entries, lines)
        # Same scenes, same values: each pipeline is one line, not one per scene.
        self.assertLessEqual(lines, 2 * 4)

    def test_one_palette_a_fixed_colour_per_pipeline_and_layout(self):
        series = sweep_rows.Series(sweep_rows_fixture())
        styles = {k: chart_style.series_style(series, k) for k in series.keys}
        self.assertEqual(len({s["color"] for s in styles.values()}), 4)
        self.assertEqual(len({s["marker"] for s in styles.values()}), 4)
        # The same series keeps its colour whatever else the sweep ran, even where its layout
        # is not part of the key (a sweep of the tree megakernel alone has the key "mega").
        alone = sweep_rows.Series([r for r in sweep_rows_fixture() if r["layout"] == "tree"
                                   and r["pipeline"] == "mega"])
        self.assertEqual(alone.keys, ["mega"])
        self.assertEqual(chart_style.series_style(alone, "mega")["color"],
                         styles["mega/tree"]["color"])
        two = sweep_rows.Series([r for r in sweep_rows_fixture() if r["pipeline"] != "queue"])
        self.assertEqual(chart_style.series_style(two, "wave"), styles["wave"])
        # A memory budget keeps its pipeline's colour and gets a line style of its own.
        budget = sweep_rows.Series(sweep_rows_fixture() + [
            row("wave", "wavefront", "tree", "spheres", 2, memory_budget=32 * 2**20)])
        plain, small = (chart_style.series_style(budget, k) for k in ("wave", "wave/32MiB"))
        self.assertEqual(plain["color"], small["color"])
        self.assertNotEqual(plain["linestyle"], small["linestyle"])

    def test_a_cell_not_measured_is_marked_not_left_as_a_line_that_stops(self):
        rows = [r for r in sweep_rows_fixture(("bounces",))
                if not (r["layout"] == "weighted" and r["bounces"] >= 3)]
        fig = charts.time_vs_bounces(META, rows)
        crosses = [line for ax in fig.axes for line in ax.lines
                   if line.get_marker() == chart_style.MISSING_MARKER]
        # The weighted layout missed B = 3 and 4 in both scenes: one row of crosses a panel.
        self.assertEqual(sorted(len(c.get_xdata()) for c in crosses), [2, 2])
        self.assertEqual({c.get_color() for c in crosses},
                         {chart_style.SERIES_STYLES[("mega", "weighted")][0]})

    def test_a_scene_cut_short_is_marked_over_the_whole_span_not_bridged(self):
        # A sweep stopped by its time limit: the second scene has B = 0 and 1 only, while the
        # first ran 0..4. Its lines must not stop at 1 unmarked (nor be drawn across a gap):
        # every series gets crosses at B = 2, 3 and 4 in that panel.
        rows = sweep_rows_fixture(("bounces",))
        scenes = sorted({r["scene"] for r in rows})
        self.assertEqual(len(scenes), 2)
        rows = [r for r in rows if not (r["scene"] == scenes[1] and r["bounces"] >= 2)]
        fig = charts.time_vs_bounces(META, rows)
        cut = [ax for ax in fig.axes if ax.get_title().startswith(scenes[1])][0]
        crosses = [line for line in cut.lines if line.get_marker() == chart_style.MISSING_MARKER]
        self.assertEqual(len(crosses), 4)  # one row per series
        for c in crosses:
            self.assertEqual(list(c.get_xdata()), [2, 3, 4])
        whole = [ax for ax in fig.axes if ax.get_title().startswith(scenes[0])][0]
        self.assertEqual([line for line in whole.lines
                          if line.get_marker() == chart_style.MISSING_MARKER], [])

    def test_kernel_breakdown_has_a_panel_per_series_and_no_second_axis(self):
        fig = charts.kernel_breakdown(META, sweep_rows_fixture(("bounces",)))
        panels = [ax for ax in fig.axes if ax.patches]
        self.assertEqual(len(panels), 2 * 4)  # two scenes, four series
        self.assertEqual([ax for ax in fig.axes if ax.get_ylabel().endswith("(log)")], [])

    def test_speed_chart_names_a_layout_without_accuracy_cells(self):
        rows = sweep_rows_fixture(("bounces",))
        rows += [row(p, t, lay, "spheres", b, group="accuracy", rmse=0.1 / (1 + b), psnr_db=20,
                     reference={"bounces": 8}) for p, t, lay in PIPES if lay != "weighted"
                 for b in range(3)]
        fig = charts.speed_vs_accuracy(META, rows)
        texts = [t.get_text() for t in fig.axes[-1].get_legend().get_texts()]
        self.assertIn("megakernel (weighted): not measured in this sweep's accuracy cells", texts)

    def test_crossover_star_only_at_a_win_beyond_the_spread(self):
        from rtlab_report import charts_crossover
        rows = crossover_fixture()
        for r in rows:  # every cell's frames spread by 30%: the queue's 0.8 is a tie
            r.update(device_ms_min=r["device_ms"] * 0.85, device_ms_max=r["device_ms"] * 1.15)
        fig = charts_crossover.crossover_chart(META, rows)
        stars = [line for ax in fig.axes[:2] for line in ax.lines if line.get_marker() == "*"]
        self.assertEqual(stars, [])
        fig = charts_crossover.crossover_chart(META, crossover_fixture())
        stars = [line for ax in fig.axes[:2] for line in ax.lines if line.get_marker() == "*"]
        # At K = 4, drawn a little apart in x (charts_crossover's dodge) so points never overprint.
        self.assertEqual([round(s.get_xdata()[0]) for s in stars], [4, 4])

    def test_pipelines_have_distinct_colours_in_line_charts(self):
        fig = charts.time_vs_bounces(META, sweep_rows_fixture())
        colours = {line.get_color() for line in fig.axes[0].lines}
        self.assertEqual(len(colours), 4)

    def test_log_axes_have_several_labels_in_one_style(self):
        fig = charts.time_vs_resolution(META, sweep_rows_fixture())
        fig.canvas.draw()
        for ax in fig.axes[:2]:
            for axis in (ax.xaxis, ax.yaxis):
                labels = [t.get_text() for t in axis.get_ticklabels() if t.get_text()]
                self.assertGreater(len(labels), 1, labels)
                self.assertTrue(all("10^" in t for t in labels) or
                                not any("10^" in t for t in labels), labels)

    def test_a_narrow_log_axis_gets_plain_labels(self):
        for lo, hi in ((90, 140), (0.23, 1.6), (0.03, 500)):
            fig, ax = chart_style.plt.subplots()
            ax.plot([1, 2], [lo, hi])
            ax.set_yscale("log")
            chart_style.log_ticks(ax)
            fig.canvas.draw()
            labels = [t.get_text() for t in ax.yaxis.get_ticklabels() if t.get_text()]
            self.assertGreaterEqual(len(labels), 3, labels)
            self.assertFalse(any("10^" in t or "times" in t for t in labels), labels)


def texts_overlap(fig):
    """Pairs of overlapping labels inside any axes, after a draw."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    out = []
    for ax in fig.axes:
        boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in ax.texts
                 if t.get_visible() and t.get_text()]
        for i, (a, box_a) in enumerate(boxes):
            # 2 px: labels that touch read as one, as if they overlapped.
            out += [(a, b) for b, box_b in boxes[i + 1:]
                    if chart_style.boxes_overlap(box_a, box_b, 2)]
    return out


@unittest.skipUnless(HAVE_MPL, "matplotlib is not installed")
class CommittedChartsTest(unittest.TestCase):
    """The charts of the committed result sets: labels must not collide."""
    SET = os.path.join(ROOT, "results", "nvidia-h100-80gb-hbm3")

    def tearDown(self):
        chart_style.plt.close("all")

    def test_speed_vs_accuracy_labels_do_not_overlap(self):
        meta, rows = charts.load(os.path.join(self.SET, "full.json"))
        fig = charts.speed_vs_accuracy(meta, rows)
        self.assertEqual(texts_overlap(fig), [])
        self.assertGreater(sum(len(ax.texts) for ax in fig.axes), 6)

    def test_limits_labels_do_not_overlap(self):
        from rtlab_report import charts_limits
        meta, rows = charts.load(os.path.join(self.SET, "limits.json"))
        fig = charts_limits.limits_chart(meta, rows)
        self.assertEqual(texts_overlap(fig), [])


class MapTest(unittest.TestCase):
    """rtlab_report/charts_map.py: the winner of each map setting, its margin, ties inside the frame
    spread, and settings some design missed left out of the win count."""

    def rows(self):
        out = []
        for scene, times in [("map/map-s4-x50-o8-m16", {"mega": (9.0, 8.8, 9.2), "queue": (3.0, 2.9, 3.1)}),
                             ("map/map-s64-x0-o8-m16", {"mega": (2.0, 1.9, 2.1), "queue": (2.05, 1.95, 2.2)}),
                             ("map/map-s256-x0-o8-m16", {"mega": (1.0, 1.0, 1.0)})]:
            for pipe, (ms, lo, hi) in times.items():
                r = row(pipe, pipe, "tree", scene, 4, 1920, 1080, group="map")
                r.update(device_ms=ms, device_ms_min=lo, device_ms_max=hi)
                if pipe == "mega" and "s4-" in scene:
                    r["extras"] = {"warp_lanes_active": 7.25}
                out.append(r)
            if scene.endswith("s256-x0-o8-m16"):
                out.append(dict(row("queue", "queue", "tree", scene, 4, 1920, 1080, group="map"),
                                status="error", failure="timeout"))
        return out

    def test_winner_margin_ties_and_missing(self):
        m = load_script("charts_map")
        series, grid = m.cells(self.rows())
        keys = series.keys
        self.assertEqual(sorted(grid), [(4, 50, 8, 16, 0), (64, 0, 8, 16, 0), (256, 0, 8, 16, 0)])
        winner, runner, margin, tie = m.verdict(grid[(4, 50, 8, 16, 0)], keys)
        self.assertEqual((winner, runner, tie), ("queue", "mega", False))
        self.assertAlmostEqual(margin, 3.0)
        self.assertTrue(m.verdict(grid[(64, 0, 8, 16, 0)], keys)[3])  # 2.0 vs 2.05, ranges overlap
        self.assertIsNone(m.verdict(grid[(256, 0, 8, 16, 0)], keys))  # the queue timed out
        with tempfile.TemporaryDirectory() as d:
            m.table(META, series, grid, keys, os.path.join(d, "map.md"))
            text = open(os.path.join(d, "map.md")).read()
        self.assertIn("Settings where every design ran: 2. Wins there: queue 1, ties 1.", text)
        self.assertIn("| 256 | 0% | 8 | 1.000 | missing | not all ran | - |", text)
        # A megakernel's busy lanes sit in brackets beside its own time.
        self.assertIn("| 4 | 50% | 8 | 9.000 (7.2) | 3.000 | queue | 3.00x |", text)

    def test_drop_leaves_out_rows_by_a_field(self):
        m = load_script("charts_map")
        rows = [{"pipeline": "persist", "persistent_schedule": "auto", "persistent_groups": 2},
                {"pipeline": "persist", "persistent_schedule": "flags", "persistent_groups": 4},
                {"pipeline": "mega"}]
        kept = m.drop_rows(rows, ["persistent_schedule=auto"])
        self.assertEqual([r.get("persistent_schedule") for r in kept], ["flags", None])
        self.assertEqual(len(m.drop_rows(rows, ["persistent_groups=4", "pipeline=mega"])), 1)

    def test_mesh_walls_are_their_own_settings_with_a_triangles_column(self):
        m = load_script("charts_map")
        rows = []
        for scene, times in [("map/map-s16-t20-x50-o8-m16", {"mega": 9.0, "queue": 3.0}),
                             ("map/map-s16-t320-x50-o8-m16", {"mega": 4.0, "queue": 5.0})]:
            for pipe, ms in times.items():
                r = row(pipe, pipe, "tree", scene, 4, 1920, 1080, group="map-mesh")
                r.update(device_ms=ms, device_ms_min=ms, device_ms_max=ms)
                rows.append(r)
        series, grid = m.cells(rows)
        self.assertEqual(sorted(grid), [(16, 50, 8, 16, 20), (16, 50, 8, 16, 320)])
        self.assertEqual(m.verdict(grid[(16, 50, 8, 16, 320)], series.keys)[0], "mega")
        with tempfile.TemporaryDirectory() as d:
            m.table(META, series, grid, series.keys, os.path.join(d, "map.md"))
            text = open(os.path.join(d, "map.md")).read()
        self.assertIn("| size px | triangles | mirrors+glass |", text)
        self.assertIn("| 16 | 320 | 50% | 8 | 4.000 | 5.000 | mega | 1.25x |", text)

    def test_a_map_joined_from_two_binaries_names_both_commits(self):
        m = load_script("charts_map")
        rows = [dict(r, commit=c) for r, c in zip(self.rows(), ["9e9a1ebb88a9", "9e9a1ebb88a9",
                                                               "8c4e049bdf7b"])]
        self.assertEqual(m.commits_of({"commit": "8c4e049bdf7b"}, rows), "9e9a1eb, 8c4e049")
        self.assertEqual(m.commits_of({"commit": "8c4e049bdf7b"}, rows[:2]), "9e9a1ebb88a9")
        self.assertEqual(m.commits_of({"commit": "8c4e049bdf7b"}, []), "8c4e049bdf7b")


class PredictEvalTest(unittest.TestCase):
    """rtlab_report/predict_eval.py: the busy-lane threshold fitted between the settings the queue won
    and those it lost, the score on rows it was not fitted to, and ties between two designs of
    one kind still counted."""

    def load(self):
        m = load_script("predict_eval")
        return m

    def rows(self, times):
        out = []
        for scene, per in times.items():
            for pipe, ms in per.items():
                r = row(pipe, pipe, "tree", scene, 4, 1920, 1080, group="map")
                r.update(device_ms=ms, device_ms_min=ms * 0.99, device_ms_max=ms * 1.01)
                out.append(r)
        return out

    def test_fit_and_score(self):
        m = self.load()
        fit = self.rows({"map/a": {"mega": 9.0, "wave": 5.0, "queue": 3.0},   # queue at 10 lanes
                         "map/b": {"mega": 2.0, "wave": 2.01, "queue": 3.0},  # mega and wave tie
                         "map/c": {"mega": 4.0, "wave": 3.0, "queue": 2.0}})  # queue at 20 lanes
        test = self.rows({"map/d": {"mega": 1.0, "wave": 1.2, "queue": 1.1},  # queue loses at 28
                          "map/e": {"mega": 1.3, "wave": 1.2, "queue": 1.0}}) # queue wins at 30
        lanes = {"map/a": 10.0, "map/b": 31.0, "map/c": 20.0, "map/d": 28.0, "map/e": 30.0}
        predictions = {k: {"busy_lanes": v} for k, v in lanes.items()}
        with tempfile.TemporaryDirectory() as d:
            for name, rows in (("fit.jsonl", fit), ("test.jsonl", test)):
                with open(os.path.join(d, name), "w") as f:
                    f.writelines(json.dumps(r) + "\n" for r in rows)
            _, fitted = m.settings([os.path.join(d, "fit.jsonl")])
            _, scored = m.settings([os.path.join(d, "test.jsonl")])
        points = [(lanes[s], m.is_queue(w)) for s, w, u, _, tie, *_ in fitted if not m.undecided(w, u, tie)]
        self.assertEqual(sorted(points), [(10.0, True), (20.0, True), (31.0, False)])
        threshold = m.fit_threshold(points)
        self.assertAlmostEqual(threshold, 25.5)  # halfway between 20 and 31
        lines, hits, count, ties, missing, worst = m.score(scored, predictions, threshold)
        self.assertEqual((hits, count, ties, missing), (1, 2, 0, 0))
        self.assertAlmostEqual(worst, 1.2)  # map/e: the best tree design (wave, 1.2) over 1.0
        self.assertIn("**no** (1.20x slower)", "\n".join(lines))

    def test_a_partial_setting_tied_within_one_kind_is_still_scored(self):
        # The weighted megakernel did not run; the tree megakernel and the tree wavefront tie
        # (2.00 and 2.01, spreads 0.04) and both beat the queue: a tree design wins either way.
        m = self.load()
        rows = self.rows({"map/p": {"mega": 2.0, "wave": 2.01, "queue": 3.0}})
        rows.append(dict(row("mega", "mega", "weighted", "map/p", 4, 1920, 1080, group="map"),
                         status="error", failure="timeout"))
        with tempfile.TemporaryDirectory() as d:
            with open(os.path.join(d, "p.jsonl"), "w") as f:
                f.writelines(json.dumps(r) + "\n" for r in rows)
            _, found = m.settings([os.path.join(d, "p.jsonl")])
        self.assertEqual(len(found), 1)
        scene, winner, runner, _, tie, *_, partial = found[0]
        self.assertEqual((scene, tie, partial), ("map/p", True, "partial"))
        self.assertFalse(m.undecided(winner, runner, tie))


class RegisterStudyTest(unittest.TestCase):
    """rtlab_report/register_study.py: occupancy from registers as the map's table derives it, and a
    variant's time a tie when its frames' range overlaps the plain build's."""

    def load(self):
        m = load_script("register_study")
        return m

    def test_occupancy(self):
        m = self.load()
        self.assertEqual(m.occupancy(142), (12, 12 / 64))  # the weighted megakernel: 19%
        self.assertEqual(m.occupancy(117), (16, 0.25))
        self.assertEqual(m.occupancy(32), (64, 1.0))

    def test_table(self):
        def rows(regs, ms, spread, opts):
            r = row("mega", "mega", "weighted", "map/a", 4, 1920, 1080)
            r.update(status="ok", device_ms=ms, device_ms_min=ms - spread, device_ms_max=ms + spread,
                     cl_options=opts, kernel_resources={"Megakernel_Render.registers": regs})
            return [r]
        with tempfile.TemporaryDirectory() as d:
            for name, rs in (("plain", rows(142, 10.0, 0.1, "")),
                             ("packed-stack", rows(120, 8.0, 0.1, "-DRT_PACKED_STACK")),
                             ("outline-query", rows(100, 10.05, 0.1, "-DRT_OUTLINE_QUERY"))):
                os.makedirs(os.path.join(d, name))
                with open(os.path.join(d, name, "rows.jsonl"), "w") as f:
                    f.writelines(json.dumps(r) + "\n" for r in rs)
            out = subprocess.run([sys.executable, TOOL, "register-study", d],
                                 capture_output=True, text=True, check=True).stdout
        self.assertIn("| plain | `-` | 142 | 0/0 | 12 | 19% | 10.000 |", out)
        self.assertIn("| packed-stack | `-DRT_PACKED_STACK` | 120 | 0/0 | 16 | 25% | 8.000 (0.80×) |", out)
        self.assertIn("10.050 (tie)", out)


class PersistTest(unittest.TestCase):
    """charts_persist.py: the best persistent schedule per scene and its speed-up over the
    weighted megakernel (as built and at its better register cap), a tie inside the frame spread
    said as one, the refill scan kept out."""

    @staticmethod
    def cell(pipe, scene, ms, spread=0.01, **extra):
        r = {"pipeline": pipe, "scene": scene, "layout": extra.pop("layout", "tree"),
             "width": 64, "height": 32, "bounces": 4, "status": "ok", "device_ms": ms,
             "device_ms_min": ms - spread, "device_ms_max": ms + spread,
             "persistent_regroup": "off", "persistent_lanes": 0, "persistent_groups": 4,
             "persistent_refill": 1}
        r.update(extra)
        return r

    def rows(self):
        c = self.cell
        return [c("mega", "walls", 10.0, layout="weighted"),
                c("mega", "walls", 8.0, layout="weighted", max_registers=64),
                c("persist", "walls", 5.0),
                c("persist", "walls", 4.0, persistent_regroup="pattern"),
                c("persist", "walls", 1.0, persistent_refill=8),  # a refill scan: no series
                c("queue", "walls", 2.0),
                c("mega", "coherent", 1.0, layout="weighted"), c("persist", "coherent", 1.005),
                c("persist", "coherent", 1.2, persistent_loop="nested"),
                c("persist", "coherent", 1.5, persistent_regroup="material")]

    def run_script(self, rows):
        return run_chart("persist-charts", rows, "persist")

    def test_rows_that_name_a_schedule_read_as_the_older_fields(self):
        """Rows since the schedules became units say persistent_schedule; the labels are those of
        the older rows that set the same schedule by its parts."""
        sys.path.insert(0, os.path.dirname(TOOL))
        from rtlab_report import charts_persist as cp
        c = self.cell
        for new, old in [
                (c("persist", "w", 1.0, persistent_schedule="flat"), c("persist", "w", 1.0)),
                (c("persist", "w", 1.0, persistent_schedule="nested"),
                 c("persist", "w", 1.0, persistent_loop="nested")),
                (c("persist", "w", 1.0, persistent_schedule="regrouped", persistent_lanes=256),
                 c("persist", "w", 1.0, persistent_regroup="pattern", persistent_lanes=256)),
                (c("persist", "w", 1.0, persistent_schedule="bounce", persistent_lanes=512),
                 c("persist", "w", 1.0, persistent_loop="bounce", persistent_batch=1024,
                   persistent_lanes=512))]:
            self.assertEqual(cp.series_of(new), cp.series_of(old))
            self.assertIsNotNone(cp.series_of(new))

    def test_best_schedule_speed_up_and_tie(self):
        d, p = self.run_script(self.rows())
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist.md")).read()
        walls = next(line for line in md.splitlines() if line.startswith("| `walls`"))
        # Over the default weighted build, and over the better of it and the capped one.
        self.assertTrue(walls.endswith("| regrouped by pattern, 128 lanes | 2.50x | 2.00x | — |"),
                        walls)
        coherent = next(line for line in md.splitlines() if line.startswith("| `coherent`"))
        self.assertTrue(coherent.endswith("| flat | 1.00x (tie) | 1.00x (tie) | — |"), coherent)
        # The nested loop is a series of its own, not taken for the flat loop.
        self.assertIn("persist, nested loop", md)
        self.assertIn("| 1.20 |", coherent)
        self.assertNotIn("1.00", walls, "the refill scan is no series")
        if HAVE_MPL:
            self.assertGreater(os.path.getsize(os.path.join(d, "persist.png")), 10000)

    def test_a_sweep_over_pixel_orders_is_tabled_by_order(self):
        c = self.cell
        rows = [c("mega", "walls", 10.0, layout="weighted"), c("queue", "walls", 2.0),
                c("persist", "walls", 5.0, persistent_tile="8x4"),
                c("persist", "walls", 4.0, persistent_tile="4x16"),
                c("persist", "walls", 2.5, persistent_tile="8x4", persistent_regroup="pattern"),
                c("persist", "walls", 2.55, persistent_tile="4x16", persistent_regroup="pattern")]
        d, p = self.run_script(rows)
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist.md")).read()
        self.assertIn("| scene | schedule | 8x4 | 4x16 | best | speed-up |", md)
        lines = md.splitlines()
        flat = next(line for line in lines if line.startswith("| `walls` | flat |"))
        self.assertEqual(flat, "| `walls` | flat | 5.000 | 4.000 | 4x16 | 2.50x | 10.000 | 2.000 |")
        pattern = next(line for line in lines if "regrouped by pattern" in line)
        self.assertIn("| 2.500 | 2.550 | 8x4 | 4.00x |", pattern)
        if HAVE_MPL:
            self.assertGreater(os.path.getsize(os.path.join(d, "persist.png")), 10000)

    def test_a_sweep_of_one_schedule_over_orders_is_tabled_by_order(self):
        c = self.cell
        rows = [c("mega", "walls", 10.0, layout="weighted"),
                c("persist", "walls", 2.5, persistent_tile="4x16", persistent_regroup="pattern"),
                c("persist", "walls", 2.6, persistent_tile="8x4", persistent_regroup="pattern"),
                c("persist", "walls", 2.4, persistent_tile="16x8", persistent_regroup="pattern")]
        d, p = self.run_script(rows)
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist.md")).read()
        self.assertIn("| scene | schedule | 4x16 | 8x4 | 16x8 | best | speed-up |", md)
        pattern = next(line for line in md.splitlines() if "regrouped by pattern" in line)
        self.assertIn("| 2.500 | 2.600 | 2.400 | 16x8 | 4.17x |", pattern)

    def test_one_schedule_in_a_second_order_is_a_series_of_its_own(self):
        # The persist sweep runs the nested loop in 4x16 and 16x8 strips: still tabled by
        # schedule, the second order a series of its own.
        c = self.cell
        rows = self.rows() + [c("persist", "coherent", 0.9, persistent_loop="nested",
                                persistent_tile="16x8")]
        d, p = self.run_script(rows)
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist.md")).read()
        self.assertNotIn("| best | speed-up |", md.splitlines()[4], "not tabled by order")
        self.assertIn("persist, nested loop, 16x8 strips", md)
        coherent = next(line for line in md.splitlines() if line.startswith("| `coherent`"))
        self.assertTrue(coherent.endswith("| nested loop, 16x8 strips | 1.11x | 1.11x | — |"),
                        coherent)

    def test_the_auto_schedule_is_a_series_of_its_own(self):
        # An auto row keeps the flags' defaults (flat, no regrouping): it must not be taken for
        # the flat loop, whose time it would replace; nor must the lockstep loop.
        c = self.cell
        rows = self.rows() + [c("persist", "walls", 3.0, persistent_schedule="auto"),
                              c("persist", "walls", 3.5, persistent_loop="lockstep")]
        d, p = self.run_script(rows)
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist.md")).read()
        self.assertIn("persist, auto schedule", md.splitlines()[4])
        self.assertIn("persist, lockstep loop", md.splitlines()[4])
        self.assertIn("| 3.50 |", next(line for line in md.splitlines()
                                        if line.startswith("| `walls`")))
        walls = next(line for line in md.splitlines() if line.startswith("| `walls`"))
        self.assertIn("| 5.00 |", walls, "the flat loop's time stays")
        self.assertTrue(walls.endswith("| auto schedule | 3.33x | 2.67x | — |"), walls)

    def test_each_bounce_setting_is_a_column_and_the_fastest_is_best(self):
        # The bounce loop's batch, lanes and groups name its series; none is taken for the flat
        # loop, and the fastest of them is the best schedule where it beats the others.
        c = self.cell
        rows = self.rows() + [
            c("persist", "walls", 3.0, persistent_loop="bounce", persistent_batch=1024,
              persistent_lanes=512, persistent_groups=1),
            c("persist", "walls", 3.2, persistent_loop="bounce", persistent_batch=512,
              persistent_lanes=256, persistent_groups=2)]
        d, p = self.run_script(rows)
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist.md")).read()
        header = md.splitlines()[4]
        self.assertIn("persist, bounce loop, 1024 px batches, 512 lanes, 1 group a unit", header)
        self.assertIn("persist, bounce loop, 512 px batches, 256 lanes, 2 groups a unit", header)
        walls = next(line for line in md.splitlines() if line.startswith("| `walls`"))
        self.assertIn("| 5.00 |", walls, "the flat loop's time stays")
        self.assertTrue(walls.endswith(
            "| bounce loop, 1024 px batches, 512 lanes, 1 group a unit | 3.33x | 2.67x | — |"),
            walls)
        if HAVE_MPL:
            self.assertGreater(os.path.getsize(os.path.join(d, "persist.png")), 10000)

    def test_the_idle_lane_bound_comes_from_the_megakernels_busy_lanes(self):
        # 32 over the weighted megakernel's busy lanes: 20 lanes bound a schedule that only
        # fills idle lanes at 1.6x; the capped build's count is not the one read.
        rows = self.rows()
        rows[0]["extras"] = {"warp_lanes_active": 20.0}
        rows[1]["extras"] = {"warp_lanes_active": 8.0}
        d, p = self.run_script(rows)
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist.md")).read()
        self.assertIn("| idle-lane bound |", md.splitlines()[4])
        walls = next(line for line in md.splitlines() if line.startswith("| `walls`"))
        self.assertTrue(walls.endswith("| 2.50x | 2.00x | 1.60x (20.0 lanes) |"), walls)
        coherent = next(line for line in md.splitlines() if line.startswith("| `coherent`"))
        self.assertTrue(coherent.endswith("| — |"), coherent)
        if HAVE_MPL:
            self.assertGreater(os.path.getsize(os.path.join(d, "persist.png")), 10000)

    def test_rows_without_their_sweep_json_say_where_they_ran(self):
        # A cut-short device call brings rows back without the sweep's JSON: the table's
        # heading takes the device, driver, commit and sweep from the rows.
        d = tempfile.mkdtemp()
        rows = [dict(r, device="GPU X", driver="9.1", commit="abc1234", sweep="persist-x")
                for r in self.rows()]
        path = write_rows(d, "rows.jsonl", rows)
        p = subprocess.run([sys.executable, TOOL, "persist-charts", path],
                           capture_output=True, text=True)
        self.assertEqual(p.returncode, 0, p.stderr)
        md = open(os.path.join(d, "persist-x.md")).read()
        self.assertTrue(md.startswith("# Persistent megakernel schedules, GPU X\n"), md[:80])
        self.assertIn("Driver 9.1, commit `abc1234`, sweep `persist-x`", md)

    def test_no_weighted_megakernel_is_one_line(self):
        rows = [r for r in self.rows() if r["pipeline"] != "mega"]
        _, p = self.run_script(rows)
        self.assertEqual(p.returncode, 1)
        self.assertIn("no weighted-megakernel rows", p.stderr)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)


class PhasesTest(unittest.TestCase):
    """rtlab_report/charts_phases.py: the persistent megakernel's phase clocks turned into
    milliseconds, beside the queue wavefront's kernels."""

    BASE = {"scene": "map/map-s16-x25-o0-m16", "status": "ok", "width": 64, "height": 32}

    def run_script(self, persist_extras, queue=True, queue_arg=None, more=()):
        d = tempfile.mkdtemp()
        base = self.BASE
        rows = [dict(base, pipeline="mega", layout="weighted", device_ms=8.0),
                dict(base, pipeline="persist", layout="weighted", device_ms=4.0,
                     persistent_loop="flat", persistent_regroup="pattern",
                     extras=persist_extras)] + list(more)
        args = []
        if queue:
            q = write_rows(d, "queue.jsonl", [dict(base, pipeline="queue", device_ms=2.0, kernel_ms={
                "extend": 0.5, "shadow": 0.25, "shade glass": 0.5, "shade miss": 0.25,
                "compact": 0.25})])
            args += ["--queue", queue_arg or f"queue={q}"]
        return run_chart("phase-charts", rows, "persist-phase", *args, d=d)

    @staticmethod
    def lines(d):
        with open(os.path.join(d, "phases.md")) as f:
            return [x.strip() for x in f if x.startswith("| `s16")]

    def test_phase_shares_of_the_device_time_and_queue_parts(self):
        # Cycles 1:4:1:0:2:0 of 4 ms: 0.5, 2, 0.5, 0, 1, 0 ms. The regrouped loop casts its
        # shadow rays in its trace; the queue's trace and shadow kernels add up beside it.
        extras = {"phase_mcycles_bookkeeping": 10.0, "phase_mcycles_trace": 40.0,
                  "phase_mcycles_trace_wait": 10.0, "phase_mcycles_shade": 20.0}
        d, p = self.run_script(extras)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(self.lines(d), [
            "| `s16-x25-o0` | weighted megakernel | 8.000 | | | | | | |",
            "| `s16-x25-o0` | regrouped by pattern | 4.000 (2.00x) | 2.00 | in the trace | 1.00 | "
            "0.50 | 0.00 | 0.50 |",
            "| `s16-x25-o0` | queue | 2.000 (4.00x) | 0.75 | 0.25 | 0.75 | — | — | 0.50 |"])
        if HAVE_MPL:
            self.assertGreater(os.path.getsize(os.path.join(d, "phases.png")), 10000)

    def test_a_bounce_loop_with_a_shadow_pass_has_its_shadow_rays_apart(self):
        # 60 units of 6 ms: trace 2, shadow pass 1, the three waits 0.5 + 0.5, shading 1,
        # filing (the staged hits and the sort) 0.5, bookkeeping 0.5.
        bounce = dict(self.BASE, pipeline="persist", layout="weighted", device_ms=6.0,
                      persistent_loop="bounce", persistent_regroup="pattern",
                      persistent_shadows="pass", extras={
                          "phase_mcycles_trace": 20.0, "phase_mcycles_shadow": 10.0,
                          "phase_mcycles_shadow_wait": 5.0, "phase_mcycles_shade": 10.0,
                          "phase_mcycles_shade_wait": 5.0, "phase_mcycles_file": 5.0,
                          "phase_mcycles_bookkeeping": 5.0})
        d, p = self.run_script({"phase_mcycles_trace": 1.0}, queue=False, more=[bounce])
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("| `s16-x25-o0` | bounce loop, sorted by pattern, shadow pass | "
                      "6.000 (1.33x) | 3.00 | 1.00 | 1.00 | 1.00 | 0.50 | 0.50 |", self.lines(d))

    def test_rows_without_clocks_are_one_line(self):
        _, p = self.run_script({"warp_steps": 5.0}, queue=False)
        self.assertEqual(p.returncode, 1)
        self.assertIn("no persistent rows with phase clocks", p.stderr)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)

    def test_a_queue_argument_without_a_label_is_one_line(self):
        _, p = self.run_script({"phase_mcycles_trace": 1.0}, queue_arg="rows.jsonl")
        self.assertEqual(p.returncode, 1)
        self.assertIn("--queue rows.jsonl: expected LABEL=ROWS.jsonl", p.stderr)


class OccupancyTest(unittest.TestCase):
    """rtlab_report/charts_occupancy.py: the queue's stage times beside the warps their kernels keep,
    estimated from registers, local memory and group size with sm_90's limits."""

    def test_resident_warps_by_registers_local_memory_and_group(self):
        from rtlab_report.charts_occupancy import resident_warps
        self.assertEqual(resident_warps(46, 420, 256), 40)     # registers: 5 groups of 8 warps
        self.assertEqual(resident_warps(46, 47524, 256), 32)   # local memory: 4 groups
        self.assertEqual(resident_warps(46, 47524, 128), 16)
        self.assertEqual(resident_warps(46, 47524, 64), 8)
        self.assertEqual(resident_warps(126, 0, 512), 16)      # the bounce loop's one kernel
        self.assertEqual(resident_warps(16, 0, 32), 32)        # at most 32 groups

    def test_stages_and_warps_a_row(self):
        base = {"scene": "map/map-s16-x25-o0-m16", "status": "ok", "width": 64, "height": 32}
        res_a = {"Queue_Extend.registers": 46, "Queue_Extend.local_bytes": 420,
                 "Queue_Shadow.registers": 61, "Queue_Shadow.local_bytes": 0,
                 "Queue_ShadeGlass.registers": 80, "Queue_ShadeMiss.registers": 18}
        res_b = dict(res_a, **{"Queue_Extend.local_bytes": 47524,
                               "Queue_Shadow.local_bytes": 47104,
                               "Queue_ShadeGlass.local_bytes": 47104,
                               "Queue_ShadeMiss.local_bytes": 47104})
        rows = [dict(base, pipeline="mega", layout="weighted", device_ms=5.0),
                dict(base, pipeline="persist", device_ms=3.0,
                     options={"persistent-lanes": 0, "persistent-loop": "bounce"},
                     kernel_resources={"Persistent_RenderBounce.registers": 126}),
                dict(base, pipeline="queue", device_ms=2.5,
                     options={"queue-group": 256, "queue-local-pad": 0}, kernel_resources=res_a,
                     kernel_ms={"extend": 0.5, "shadow": 0.8, "shade glass": 0.4,
                                "shade miss": 0.1}),
                dict(base, pipeline="queue", device_ms=3.9,
                     options={"queue-group": 128, "queue-local-pad": 47104},
                     kernel_resources=res_b,
                     kernel_ms={"extend": 0.9, "shadow": 1.5, "shade glass": 0.6,
                                "shade miss": 0.1})]
        d, p = run_chart("occupancy-charts", rows, "queue-occupancy")
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(os.path.join(d, "occupancy.md")) as f:
            lines = [x.strip() for x in f if x.startswith("| `s16")]
        self.assertEqual(lines, [
            "| `s16-x25-o0` | weighted megakernel | 5.000 | | | |",
            "| `s16-x25-o0` | persistent megakernel | 3.000 (1.67x) | one kernel: 16 warps | | |",
            "| `s16-x25-o0` | queue, groups of 256 | 2.500 (2.00x) | 0.50 (40) | 0.80 (32) | "
            "0.50 (24) |",
            "| `s16-x25-o0` | queue, groups of 128, 47104 B pad | 3.900 (1.28x) | 0.90 (16) | "
            "1.50 (16) | 0.70 (16) |"])
        if HAVE_MPL:
            self.assertGreater(os.path.getsize(os.path.join(d, "occupancy.png")), 10000)

    def test_rows_without_registers_are_one_line(self):
        _, p = run_chart("occupancy-charts", [{"scene": "spheres", "pipeline": "queue",
                                                  "status": "ok", "device_ms": 1.0,
                                                  "kernel_ms": {"extend": 0.5}}],
                         "queue-occupancy")
        self.assertEqual(p.returncode, 1)
        self.assertIn("no queue rows with kernel times and registers", p.stderr)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)

if __name__ == "__main__":
    unittest.main()
