#!/usr/bin/python3
"""Tests of scripts/nvptx-registers without clang or ptxas: its register cap is the host's
(persistentRegisterCap, whose C++ test holds the same values), it reads ptxas -v's report, an
entry's own lines and not its callees', as ptxas 13 writes it, and the calls its builds leave
out are in the kernel source, once each.
"""
import importlib.machinery
import importlib.util
import os
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PATH = os.path.join(ROOT, "scripts", "nvptx-registers")
loader = importlib.machinery.SourceFileLoader("nvptx_registers", PATH)
spec = importlib.util.spec_from_loader("nvptx_registers", loader)
nvptx = importlib.util.module_from_spec(spec)
loader.exec_module(nvptx)

# An excerpt of ptxas 13.0's -v report for sm_90: an entry that calls a function, then another.
REPORT = """ptxas info    : 0 bytes gmem
ptxas info    : Compiling entry function 'Persistent_RenderBounce' for 'sm_90'
ptxas info    : Function properties for Persistent_RenderBounce
    2464 bytes stack frame, 72 bytes spill stores, 108 bytes spill loads
ptxas info    : Used 128 registers, used 1 barriers, 2464 bytes cumulative stack size, 104 bytes smem
ptxas info    : Function properties for _Z3cosf
    0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads
ptxas info    : Compiling entry function 'Queue_ShadeMiss' for 'sm_90'
ptxas info    : Function properties for Queue_ShadeMiss
    0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads
ptxas info    : Used 16 registers, used 0 barriers
"""


class RegisterCap(unittest.TestCase):
    def test_the_hosts_values(self):
        self.assertEqual(nvptx.cap_for(128, 0), 0)
        self.assertEqual(nvptx.cap_for(256, 0), 0)
        self.assertEqual(nvptx.cap_for(512, 0), 128)
        self.assertEqual(nvptx.cap_for(1024, 0), 64)
        self.assertEqual(nvptx.cap_for(384, 0), 168)
        self.assertEqual(nvptx.cap_for(500, 0), 128)
        self.assertEqual(nvptx.cap_for(512, 96), 96)


class Report(unittest.TestCase):
    def test_each_entry_its_own_lines(self):
        kernels = nvptx.parse_ptxas(REPORT)
        self.assertEqual(kernels, {
            "Persistent_RenderBounce": {"registers": 128, "spill_stores": 72,
                                        "spill_loads": 108, "stack": 2464},
            "Queue_ShadeMiss": {"registers": 16, "spill_stores": 0, "spill_loads": 0,
                                "stack": 0},
        })

    def test_every_build_names_a_kernel_file_and_calls_that_exist(self):
        for label, source, *rest in nvptx.BUILDS:
            self.assertTrue(os.path.exists(os.path.join(ROOT, source)), label)
            calls = rest[5] if len(rest) > 5 else []
            text = nvptx.source_without(source, calls)  # exits unless each is there once
            for call in calls:
                self.assertNotIn(call, text, label)



class Accel(unittest.TestCase):
    def test_each_layout_is_the_hosts_define(self):
        with open(os.path.join(ROOT, "core", "pipeline.cpp")) as f:
            pipeline = f.read()
        self.assertEqual(sorted(nvptx.ACCELS), ["bvh", "cwbvh", "wide"])
        for name, define in nvptx.ACCELS.items():
            self.assertIn('d.push_back("%s")' % define, pipeline, name)
            self.assertNotIn(define, nvptx.WALL)

    def test_the_driver_registers_come_from_rows_of_the_same_layout(self):
        rows = [{"pipeline": "mega", "accel": "cwbvh",
                 "kernel_resources": {"Megakernel_Render.registers": 168}},
                {"pipeline": "mega", "kernel_resources": {"Megakernel_Render.registers": 126}},
                {"pipeline": "mega", "accel": "bvh", "error": "refused",
                 "kernel_resources": {"Megakernel_Render.registers": 1}}]
        mega = lambda r: r["pipeline"] == "mega"
        self.assertEqual(nvptx.measured(rows, mega)["Megakernel_Render"][0], 126)
        self.assertEqual(nvptx.measured(rows, mega, "cwbvh")["Megakernel_Render"][0], 168)
        self.assertEqual(nvptx.measured(rows, mega, "wide"), {})


class Root(unittest.TestCase):
    def test_a_folder_that_is_no_checkout_is_one_line(self):
        import subprocess
        import sys
        import tempfile
        d = tempfile.mkdtemp()
        p = subprocess.run([sys.executable, PATH, "--root", d], capture_output=True, text=True)
        self.assertNotEqual(p.returncode, 0)
        self.assertEqual(p.stderr.strip(), "scripts/nvptx-registers: " + d +
                         ": not an rtlab checkout (no persistent/handout.cl)")


if __name__ == "__main__":
    unittest.main()
