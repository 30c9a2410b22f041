// rtlab-bench's command line: a bad flag, a bad value or a mistyped flag ends in one line on
// stderr naming the flag and why, and exit status 1, as in the rtlab front end (cli_test.cpp);
// --help explains every flag; both value forms and Google Benchmark's own flags are taken.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <ostream>
#include <string>

#include "command_case.h"
#include "pipelines/registry.h"
#include "scratch_dir.h"

namespace {

struct BenchOutcome {
    int status;
    std::string out, err;
};

std::string benchPath() { return std::string(RTLAB_BIN_DIR) + "/rtlab-bench"; }

BenchOutcome runBench(const std::string& args) {
    static int calls = 0;  // one stderr file per call: CTest runs suites in parallel
    std::string errFile = rt::test::scratchPath("bench_cli_err_" + std::to_string(++calls));
    BenchOutcome r{};
    FILE* p = popen((benchPath() + " " + args + " 2>" + errFile).c_str(), "r");
    std::array<char, 4096> buf;
    while (size_t n = fread(buf.data(), 1, buf.size(), p)) r.out.append(buf.data(), n);
    int st = pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    if (FILE* f = fopen(errFile.c_str(), "r")) {
        while (size_t n = fread(buf.data(), 1, buf.size(), f)) r.err.append(buf.data(), n);
        fclose(f);
    }
    std::remove(errFile.c_str());
    return r;
}

struct BenchBadCase {
    const char* args;
    const char* expected;  // substring of the one error line
};

void PrintTo(const BenchBadCase& c, std::ostream* os) { *os << "rtlab-bench " << c.args; }

class BenchCliRejects : public ::testing::TestWithParam<BenchBadCase> {};

TEST_P(BenchCliRejects, WithOneLineAndExitStatusOne) {
    if (!std::filesystem::exists(benchPath())) GTEST_SKIP() << "rtlab-bench not built";
    const BenchBadCase& c = GetParam();
    BenchOutcome r = runBench(c.args);
    EXPECT_EQ(r.status, 1) << c.args << "\nstderr: " << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\nstderr: " << r.err;
    EXPECT_EQ(r.err.rfind("rtlab-bench: ", 0), 0u) << r.err;
    int lines = 0;
    for (char ch : r.err) lines += ch == '\n';
    EXPECT_EQ(lines, 1) << c.args << "\nstderr: " << r.err;
}

// None of these reaches a device: each is refused while the command line is read.
INSTANTIATE_TEST_SUITE_P(
    BadFlags, BenchCliRejects,
    ::testing::Values(
        BenchBadCase{"--scens=spheres", "--scens=spheres (did you mean --scenes?)"},
        BenchBadCase{"--sweep=quick --out /tmp/x --time-limt 60", "(did you mean --time-limit?)"},
        BenchBadCase{"--nosuchflag", "not expected: --nosuchflag"},
        BenchBadCase{"spheres", "not expected: spheres"},
        BenchBadCase{"--frames=0", "--frames 0: must be in 1..100000"},
        BenchBadCase{"--repeats 1001", "--repeats 1001: must be in 1..1000"},
        BenchBadCase{"--warmup=some", "--warmup some: not a number; expected 0..100"},
        BenchBadCase{"--count-rays=maybe", "--count-rays maybe: must be one of yes, no"},
        BenchBadCase{"--smoke --cell-timeout=-1", "--cell-timeout -1: must be in 0..10000000"},
        BenchBadCase{"--sweep=quick --out=/tmp/x --time-limit=soon", "--time-limit soon: not a"},
        BenchBadCase{"--sweep", "--sweep: 1 required SWEEP missing"},
        BenchBadCase{"--shard=0/2", "--shard: only with --sweep"},
        BenchBadCase{"--smoke --resume=rows.jsonl", "--resume: not with --smoke"}),
    rt::test::commandCaseName<BenchBadCase>);

TEST(BenchCli, HelpExplainsEveryFlagAndPipeline) {
    if (!std::filesystem::exists(benchPath())) GTEST_SKIP() << "rtlab-bench not built";
    BenchOutcome r = runBench("--help");
    EXPECT_EQ(r.status, 0) << r.err;
    for (const char* flag :
         {"--scenes",     "--pipelines",    "--sizes",        "--bounces", "--accels",
          "--cells",      "--device ",      "--devices",      "--repeats", "--frames",
          "--warmup",     "--count-rays",   "--cell-timeout", "--sweep",   "--out",
          "--time-limit", "--shard",        "--resume",       "--smoke",   "--scene-dir",
          "--kernel-dir", "--list-devices", "--version",      "--help",    "--benchmark_filter"})
        EXPECT_NE(r.out.find(flag), std::string::npos) << flag << " missing from\n" << r.out;
    EXPECT_NE(r.out.find(rt::pipelineRegistry().help()), std::string::npos) << r.out;
}

// --flag value and --flag=value, with a Google Benchmark flag among them (it takes its own out
// of the command line first); --benchmark_list_tests names the benchmarks without running them.
TEST(BenchCli, TakesBothValueFormsAndGoogleBenchmarkFlags) {
    if (!std::filesystem::exists(benchPath())) GTEST_SKIP() << "rtlab-bench not built";
    BenchOutcome r = runBench(
        "--scenes spheres,cornell --pipelines=mega --sizes 16x12 --bounces=1,2 --accels bvh "
        "--benchmark_list_tests=true --scene-dir " RTLAB_SOURCE_DIR "/scenes");
    EXPECT_EQ(r.status, 0) << r.err;
    for (const char* name : {"render/spheres/mega/16x12/b1/", "render/spheres/mega/16x12/b2/",
                             "render/cornell/mega/16x12/b1/", "render/cornell/mega/16x12/b2/"})
        EXPECT_NE(r.out.find(name), std::string::npos) << name << " missing from\n" << r.out;
    EXPECT_NE(r.out.find("/bvh"), std::string::npos) << r.out;
}

}  // namespace
