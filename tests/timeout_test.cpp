// Nothing waits forever: a cell that passes the cell time limit (--cell-timeout) becomes a row
// with status "error" and failure "timeout", the exit status is 1, and the rows measured before it
// are kept; --resume then goes on past it. Also the smoke check that guards every GPU result.
// The slow cell is slow on any device: 4096x4096 at 16x16 samples a pixel, fifty frames (about
// 200 G rays), against a limit of a few seconds.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "pipelines/registry.h"
#include "scratch_dir.h"
#include "test_device.h"

namespace {

namespace fs = std::filesystem;

struct Outcome {
    int status;
    std::string out;
};

// Runs a command line, stderr to a file of its own; stdout is returned.
Outcome shell(const std::string& cmd) {
    static int calls = 0;
    std::string err = rt::test::scratchPath("timeout_err_" + std::to_string(++calls) + ".txt");
    Outcome r{};
    FILE* p = popen((cmd + " 2>" + err).c_str(), "r");
    std::array<char, 4096> buf;
    while (size_t n = fread(buf.data(), 1, buf.size(), p)) r.out.append(buf.data(), n);
    int st = pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    std::ifstream f(err);
    std::stringstream s;
    s << f.rdbuf();
    r.out += s.str();
    return r;
}

std::string bench() { return std::string(RTLAB_BIN_DIR) + "/rtlab-bench"; }

// The test process's own device, by index, for the child processes.
std::string deviceFlag() { return "--device=" + std::to_string(rt::test::device().device().index); }

const char* kFast = "[fast]\nscenes = spheres\npipelines = mega\nsizes = 32x24\nbounces = 1\n";
const char* kSlow =
    "[slow]\nscenes = spheres\npipelines = mega\nsizes = 4096x4096\nbounces = 1\naa = 16\n"
    "repeats = 50\nwarmup = 0\n";
const char* kAfter = "[after]\nscenes = spheres\npipelines = mega\nsizes = 48x32\nbounces = 1\n";

std::map<std::string, nlohmann::json> rowsByGroup(const fs::path& file) {
    std::map<std::string, nlohmann::json> rows;
    std::ifstream f(file);
    for (std::string line; std::getline(f, line);) {
        nlohmann::json r = nlohmann::json::parse(line);
        rows[r["groups"][0].get<std::string>()] = r;
    }
    return rows;
}

TEST(CellTimeout, SlowSweepCellBecomesATimeoutRowAndResumeGoesOn) {
    if (!fs::exists(bench())) GTEST_SKIP() << "rtlab-bench not built";
    fs::path dir = rt::test::scratchPath("cell_timeout/");
    std::string head = "repeats = 1\nwarmup = 0\ncount-rays = no\n";
    std::ofstream(dir / "warm") << head << kFast << kAfter;
    std::ofstream(dir / "slow") << head << kFast << kSlow << kAfter;
    std::string common = " " + deviceFlag() + " --scene-dir=" RTLAB_SOURCE_DIR "/scenes";
    // The programs are built (and cached) first, so that only the slow cell's frames can pass
    // the limit below.
    Outcome warm = shell(bench() + " --sweep=" + (dir / "warm").string() +
                         " --out=" + (dir / "w").string() + common);
    ASSERT_EQ(warm.status, 0) << warm.out;

    Outcome slow = shell(bench() + " --sweep=" + (dir / "slow").string() +
                         " --out=" + (dir / "s").string() + common + " --cell-timeout=5");
    EXPECT_EQ(slow.status, 1) << slow.out;
    EXPECT_NE(slow.out.find("1 cell(s) timed out"), std::string::npos) << slow.out;
    auto rows = rowsByGroup(dir / "s" / "rows.jsonl");
    ASSERT_TRUE(rows.count("fast") && rows.count("slow")) << slow.out;
    EXPECT_EQ(rows["fast"]["status"], "ok");
    EXPECT_EQ(rows["slow"]["status"], "error");
    EXPECT_EQ(rows["slow"]["failure"], "timeout");
    EXPECT_NE(rows["slow"]["error"].get<std::string>().find("did not finish within 5 s"),
              std::string::npos)
        << rows["slow"]["error"];
    std::ifstream metaFile(dir / "s" / "sweep.json");
    nlohmann::json meta = nlohmann::json::parse(metaFile);
    EXPECT_EQ(meta["timed_out"], 1);
    EXPECT_EQ(meta["cell_timeout_s"], 5);
    // The device was busy with the slow frames: the sweep stopped there rather than measure the
    // next cell beside them.
    EXPECT_FALSE(rows.count("after"));
    EXPECT_EQ(meta["complete"], false);
    EXPECT_TRUE(meta.contains("stopped_by"));

    // --resume skips the cells measured and the one that timed out, and runs the rest.
    Outcome resumed =
        shell(bench() + " --sweep=" + (dir / "slow").string() + " --out=" + (dir / "r").string() +
              common + " --cell-timeout=5 --resume=" + (dir / "s" / "rows.jsonl").string());
    EXPECT_EQ(resumed.status, 0) << resumed.out;
    auto more = rowsByGroup(dir / "r" / "rows.jsonl");
    ASSERT_EQ(more.size(), 1u) << resumed.out;
    EXPECT_EQ(more["after"]["status"], "ok");
}

// `rtlab sweep` shares the loop: the same row, its JSON and CSV written, exit status 1.
TEST(CellTimeout, RtlabSweepWritesTheTimeoutRow) {
    fs::path dir = rt::test::scratchPath("cell_timeout_rtlab/");
    std::string head = "repeats = 1\nwarmup = 0\ncount-rays = no\n";
    std::ofstream(dir / "warmcell") << head << kFast;
    std::ofstream(dir / "slowcell") << head << kFast << kSlow;
    std::string rtlab = std::string(RTLAB_BIN_DIR) + "/rtlab";
    Outcome warm = shell(rtlab + " sweep " + (dir / "warmcell").string() + " --out " +
                         (dir / "warm").string() + " --no-charts " + deviceFlag());
    ASSERT_EQ(warm.status, 0) << warm.out;
    Outcome r = shell(rtlab + " sweep " + (dir / "slowcell").string() + " --out " +
                      (dir / "out").string() + " --no-charts --cell-timeout 5 " + deviceFlag());
    EXPECT_EQ(r.status, 1) << r.out;
    std::ifstream f(dir / "out" / "slowcell.json");
    ASSERT_TRUE(f) << r.out;
    nlohmann::json set = nlohmann::json::parse(f);
    ASSERT_EQ(set["rows"].size(), 2u) << r.out;
    EXPECT_EQ(set["rows"][0]["status"], "ok");
    EXPECT_EQ(set["rows"][1]["failure"], "timeout");
    EXPECT_TRUE(fs::exists(dir / "out" / "slowcell.csv"));
}

// Google Benchmark mode: the repetition fails with "timeout", the later ones are not run, and
// the exit status is 1.
TEST(CellTimeout, SlowBenchmarkTimesOut) {
    if (!fs::exists(bench())) GTEST_SKIP() << "rtlab-bench not built";
    Outcome r = shell(bench() +
                      " --scenes=spheres --pipelines=mega,wave --sizes=4096x4096 "
                      "--bounces=1 --repeats=1 --frames=100000 --warmup=0 --count-rays=no "
                      "--cell-timeout=5 --scene-dir=" RTLAB_SOURCE_DIR "/scenes " +
                      deviceFlag());
    EXPECT_EQ(r.status, 1) << r.out;
    EXPECT_NE(r.out.find("timeout: did not finish within 5 s"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("timed out before it"), std::string::npos) << r.out;  // wave: not run
}

TEST(CellTimeout, RejectsANegativeLimit) {
    if (!fs::exists(bench())) GTEST_SKIP() << "rtlab-bench not built";
    Outcome r = shell(bench() + " --smoke --cell-timeout=-1");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.out.find("--cell-timeout -1: must be in 0..10000000"), std::string::npos) << r.out;
}

// The smoke check on this device, one scene and two structures: every line PASS, one per cell.
TEST(Smoke, EveryCellPassesOnTheTestDevice) {
    if (!fs::exists(bench())) GTEST_SKIP() << "rtlab-bench not built";
    Outcome r = shell(bench() +
                      " --smoke --scenes=cornell --sizes=24x16 --accels=none,bvh "
                      "--scene-dir=" RTLAB_SOURCE_DIR "/scenes " +
                      deviceFlag());
    EXPECT_EQ(r.status, 0) << r.out;
    int pass = 0, fail = 0;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
        pass += line.rfind("PASS  cornell 24x16 ", 0) == 0;
        fail += line.rfind("FAIL", 0) == 0;
    }
    // Every registered device pipeline in each of its variants, two structures.
    const int variants = int(rt::pipelineRegistry().variants(true).size());
    EXPECT_EQ(pass, 2 * variants) << r.out;
    EXPECT_EQ(fail, 0) << r.out;
    std::string total = std::to_string(2 * variants);
    EXPECT_NE(r.out.find("smoke: " + total + " of " + total + " cells passed"), std::string::npos)
        << r.out;
}

}  // namespace
