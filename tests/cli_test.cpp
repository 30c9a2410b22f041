// The rtlab executable: bad input ends in one line on stderr naming the file or flag, a non-zero
// exit status, and no crash; good input writes the image.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "command_case.h"
#include "core/cl_runtime.h"
#include "core/version.h"
#include "pipelines/registry.h"
#include "scratch_dir.h"

namespace {

struct Result {
    int status;
    std::string err, out;
};

Result run(const std::string& args) {
    // One stderr file per call and process: CTest runs the cases in parallel.
    static int calls = 0;
    std::string errFile = rt::test::scratchPath("err_" + std::to_string(++calls) + ".txt");
    std::string cmd = std::string(RTLAB_BIN_DIR) + "/rtlab " + args + " 2>" + errFile;
    Result r{};
    FILE* p = popen(cmd.c_str(), "r");
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

int lines(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

struct BadCase {
    const char* args;
    const char* expected;  // substring of the one error line
};

// Test names and failure messages show the command line, not gtest's "16-byte object <...>".
void PrintTo(const BadCase& c, std::ostream* os) { *os << "rtlab " << c.args; }

class CliRejects : public ::testing::TestWithParam<BadCase> {};

TEST_P(CliRejects, WithOneLineAndNonZeroExit) {
    const BadCase& c = GetParam();
    Result r = run(c.args);
    EXPECT_EQ(r.status, 1) << c.args << ": every usage or input error exits with status 1";
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\nstderr: " << r.err;
    EXPECT_EQ(lines(r.err), 1) << c.args << "\nstderr: " << r.err;
}

const std::string kOut = " -o " + rt::test::scratchPath("out.png");

INSTANTIATE_TEST_SUITE_P(
    BadInput, CliRejects,
    ::testing::Values(
        BadCase{"render scenes/nope.json --pipeline cpu -o /tmp/x.png", "scenes/nope.json"},
        BadCase{"render scenes/spheres.json --size 0x10 -o /tmp/x.png", "--size 0x10"},
        BadCase{"render scenes/spheres.json --size big -o /tmp/x.png", "--size big"},
        BadCase{"render scenes/spheres.json --bounces 99 -o /tmp/x.png", "--bounces 99"},
        BadCase{"render scenes/spheres.json --bounces -1 -o /tmp/x.png", "--bounces"},
        BadCase{"render scenes/spheres.json --aa 0 -o /tmp/x.png", "--aa 0"},
        BadCase{"render scenes/spheres.json --shadow-samples 1000 -o /tmp/x.png",
                "--shadow-samples 1000"},
        BadCase{"render scenes/spheres.json --pipeline gpu -o /tmp/x.png", "--pipeline"},
        BadCase{"sweep quick --no-charts --out /tmp/x --devices nosuchdevice",
                "--devices nosuchdevice: 'nosuchdevice': no device name"},
        BadCase{"sweep quick --no-charts --out /tmp/x --devices 0,97",
                "--devices 0,97: 97: no such"},
        BadCase{"sweep quick --no-charts --out /tmp/x --device 0 --devices 0",
                "--device and --devices: give one"},
        BadCase{"sweep quick --no-charts --out /tmp/x --shard 0/0", "--shard 0/0: N must be"},
        BadCase{"sweep quick --no-charts --out /tmp/x --shard 3/2", "--shard 3/2: i must be less"},
        BadCase{"sweep quick --no-charts --out /tmp/x --shard x/y", "--shard x/y: 'x' is not"},
        BadCase{"render scenes/spheres.json --device 97 -o /tmp/x.png", "--device 97"},
        BadCase{"render scenes/spheres.json --device nosuchdevice -o /tmp/x.png", "nosuchdevice"},
        BadCase{"render scenes/spheres.json -o /no/such/dir/x.png", "/no/such/dir"},
        BadCase{"render scenes/spheres.json -o /tmp/x.bmpx", "unsupported image type"},
        BadCase{"render scenes/spheres.json --pipeline wave --memory-budget 10 -o /tmp/x.png",
                "exceeds --memory-budget (10 B)"},
        BadCase{"render scenes/spheres.json --pipeline wave --memory-budget 100K --bounces 8 "
                "-o /tmp/x.png",
                "the highest bounce limit that fits is 1"},
        BadCase{"render scenes/spheres.json --pipeline wave --memory-budget lots -o /tmp/x.png",
                "--memory-budget lots"},
        BadCase{"render scenes/spheres.json --pipeline mega --bounces 15 -o /tmp/x.png",
                "--layout weighted"},
        BadCase{"render scenes/spheres.json --accel kdtree -o /tmp/x.png", "--accel"},
        BadCase{"render scenes/spheres.json --offset tiny -o /tmp/x.png", "--offset tiny"},
        BadCase{"render scenes/spheres.json --offset scaled --fixed-offset -o /tmp/x.png",
                "--fixed-offset contradicts --offset scaled"},
        BadCase{"render scenes/spheres.json --max-registers 8 -o /tmp/x.png",
                "--max-registers 8: must be in 16..255"},
        BadCase{"render scenes/spheres.json --pipeline queue --pool 0 -o /tmp/x.png",
                "--pool 0: must be in 1..67108864"},
        BadCase{"render scenes/spheres.json --pipeline persist --persistent-lanes 8 -o /tmp/x.png",
                "--persistent-lanes 8: must be in 16..1024"},
        BadCase{"render scenes/spheres.json --pipeline persist --persistent-max-registers 300 "
                "-o /tmp/x.png",
                "--persistent-max-registers 300: must be in 16..255"},
        BadCase{"render scenes/spheres.json --pipeline persist --persistent-schedule often "
                "-o /tmp/x.png",
                "--persistent-schedule often: must be flat, nested, nested-16x8, regrouped, "
                "bounce, bounce-staged or auto"},
        BadCase{"render scenes/spheres.json --size 16x8 --pipeline persist --persistent-schedule "
                "auto --persistent-lanes 64 -o /tmp/x.png",
                "--persistent-schedule auto chooses --persistent-lanes itself"},
        BadCase{"render scenes/spheres.json --pipeline queue --pool 8 --bounces 6 -o /tmp/x.png",
                "use --pool 64 or more"},
        BadCase{"render scenes/spheres.json --pipeline queue --queue-launch sideways -o /tmp/x.png",
                "--queue-launch sideways: must be readback or device"},
        BadCase{"render scenes/spheres.json --pipeline queue --queue-launch device "
                "--max-launch-ms 5 -o /tmp/x.png",
                "--queue-launch device does not go with --max-launch-ms"},
        BadCase{"render scenes/mesh.json --pipeline queue --queue-packets often -o /tmp/x.png",
                "--queue-packets often: must be auto, on or off"},
        BadCase{"render scenes/cornell.json --pipeline queue --queue-shade foo -o /tmp/x.png",
                "--queue-shade foo: must be class, pattern or sort"},
        BadCase{"render scenes/mesh.json --pipeline queue --accel bvh --queue-packets on "
                "-o /tmp/x.png",
                "--queue-packets on: packets traverse the wide BVH only (use --accel wide)"},
        BadCase{"render scenes/spheres.json --pipeline queue --accel wide --queue-packets on "
                "-o /tmp/x.png",
                "--queue-packets on: packets trace triangles, and the scene has none"},
        BadCase{"render tests/data/bad_scenes/negative_radius.json -o /tmp/x.png",
                "tests/data/bad_scenes/negative_radius.json: /spheres/"},
        BadCase{"render scenes/spheres.json --kernel-dir /no/such -o /tmp/x.png", "--kernel-dir"},
        BadCase{"render scenes/spheres.json --bounce 3 -o /tmp/x.png", "did you mean --bounces?"},
        BadCase{"render scenes/spheres.json --bounce 3 -o /tmp/x.png", "see rtlab render --help"},
        BadCase{"render scenes/spheres.json --layout diagonal -o /tmp/x.png", "--layout"},
        BadCase{"render scenes/spheres.json --pipeline wave --adaptive --aa 2 -o /tmp/x.png",
                "--adaptive: the wavefront pipeline has no adaptive anti-aliasing"},
        BadCase{"render tests/data/model.fbx -o /tmp/x.png", "fbx files are not supported"},
        BadCase{"render tests/data/bad_models/points.ply -o /tmp/x.png",
                "tests/data/bad_models/points.ply: no triangles"},
        BadCase{"render tests/data/bad_models/truncated.glb -o /tmp/x.png",
                "tests/data/bad_models/truncated.glb: GLTF: Could not read the file contents"},
        // Malformed NFF: the file, the line and the reason (core/nff_loader.cpp).
        BadCase{"render tests/data/bad_nff/truncated_polygon.nff -o /tmp/x.png",
                "tests/data/bad_nff/truncated_polygon.nff: line 9: truncated polygon 'p': the file "
                "ends before its vertex 3 of 4 x"},
        BadCase{"render tests/data/bad_nff/truncated_cone.nff -o /tmp/x.png",
                "tests/data/bad_nff/truncated_cone.nff: line 9: truncated cone 'c': the file ends "
                "before its apex x"},
        BadCase{"render tests/data/bad_nff/truncated_sphere.nff -o /tmp/x.png",
                "tests/data/bad_nff/truncated_sphere.nff: line 10: sphere 's' (of line 9): "
                "expected its radius, got 's'"},
        BadCase{"render tests/data/bad_nff/truncated_viewpoint.nff -o /tmp/x.png",
                "tests/data/bad_nff/truncated_viewpoint.nff: line 1: truncated viewpoint: the file "
                "ends before its 'angle'"},
        BadCase{"render tests/data/bad_nff/unknown_keyword.nff -o /tmp/x.png",
                "tests/data/bad_nff/unknown_keyword.nff: line 9: unknown keyword 'tpp'"},
        BadCase{"render tests/data/bad_nff/polygon_two_vertices.nff -o /tmp/x.png",
                "tests/data/bad_nff/polygon_two_vertices.nff: line 9: polygon 'p' of 2 vertices "
                "(at least 3)"},
        BadCase{"render tests/data/bad_nff/nan.nff -o /tmp/x.png",
                "tests/data/bad_nff/nan.nff: line 9: sphere 's': centre y 'nan' is not a finite "
                "32-bit float"},
        BadCase{"render tests/data/bad_nff/from_equals_at.nff -o /tmp/x.png",
                "tests/data/bad_nff/from_equals_at.nff: line 3: viewpoint: 'from' and 'at' are the "
                "same point"},
        BadCase{"render tests/data/bad_nff/too_many_lights.nff -o /tmp/x.png",
                "tests/data/bad_nff/too_many_lights.nff: line 24: more than 16 lights (rtlab's "
                "limit, RT_MAX_LIGHTS)"},
        BadCase{"render scenes/spheres.json -o scenes", "scenes: is a folder"},
        BadCase{"compare scenes/spheres.json -o /no/such/dir/p", "--output-prefix /no/such/dir/p"},
        BadCase{"render scenes/spheres.json --stats-json /no/such/dir/s.json -o /tmp/x.png",
                "--stats-json /no/such/dir/s.json"},
        BadCase{"bogus", "unknown command 'bogus'"},
        // Values CLI11 cannot convert, said as rtlab says the others.
        BadCase{"render scenes/spheres.json --bounces four -o /tmp/x.png",
                "--bounces four: not a whole number"},
        BadCase{"render scenes/spheres.json --max-launch-ms soon -o /tmp/x.png",
                "--max-launch-ms soon: not a number; expected 0..1000000"},
        BadCase{"render scenes/spheres.json --max-launch-ms -3 -o /tmp/x.png",
                "--max-launch-ms -3: must be in 0..1000000"},
        BadCase{"render scenes/spheres.json --layout diagonal -o /tmp/x.png",
                "--layout diagonal: must be tree or weighted"},
        BadCase{"rendr scenes/spheres.json", "unknown command 'rendr' (did you mean render?)"},
        BadCase{"sweep nosuchsweep", "nosuchsweep: no such sweep file (give a path, or one of "},
        BadCase{"sweep quick --cell-timeout -2", "--cell-timeout -2: must be in 0..10000000"},
        BadCase{"render README.md -o /tmp/x.png", "README.md: not a scene file (a scene is a JSON"},
        BadCase{"render docs/viewer-split.png -o /tmp/x.png", "viewer-split.png: not a scene file"},
        BadCase{"predict", "scenes is required (see rtlab predict --help)"},
        BadCase{"predict scenes/nope.json", "scenes/nope.json: cannot open"},
        BadCase{"predict README.md", "README.md: not a scene file"},
        BadCase{"predict scenes/spheres.json --warps 0", "--warps 0: must be in 1..1048576"},
        BadCase{"predict scenes/spheres.json --size 0x10", "--size 0x10: width and height must"},
        BadCase{"predict scenes/spheres.json --threshold 40", "--threshold 40: must be in 0..32"},
        BadCase{"predict scenes/spheres.json --bounces 99", "--bounces 99: must be in 0..64"}),
    rt::test::commandCaseName<BadCase>);

TEST(Cli, RendersWithEveryPipeline) {
    for (const std::string& name : rt::pipelineRegistry().names()) {
        const char* p = name.c_str();
        std::string out = rt::test::scratchPath(name + ".exr");
        Result r = run(std::string("render scenes/shadows.json --size 32x24 --pipeline ") + p +
                       " --stats -o " + out);
        EXPECT_EQ(r.status, 0) << p << ": " << r.err;
        EXPECT_TRUE(std::filesystem::exists(out)) << p;
        if (std::string(p) == "wave") {
            EXPECT_NE(r.out.find("trace"), std::string::npos) << r.out;
            EXPECT_NE(r.out.find("ray tree"), std::string::npos) << r.out;
        }
        if (std::string(p) == "queue") {
            EXPECT_NE(r.out.find("pool"), std::string::npos) << r.out;
            EXPECT_NE(r.out.find("shade diffuse"), std::string::npos) << r.out;
        }
    }
}

// The queue's own flags reach it through the registry's option map: the pool it was given, the
// sizing it was asked for, and device sizing without the default launch cap (which it refuses).
TEST(Cli, QueueFlagsReachThePipeline) {
    const std::string out = rt::test::scratchPath("queue-flags.png");
    Result r =
        run("render scenes/shadows.json --size 32x24 --pipeline queue --pool 4096 "
            "--queue-launch device --queue-packets off --queue-shade sort --stats-json - -o " +
            out);
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("extras").at("pool_rays"), 4096);
    EXPECT_EQ(j.at("extras").at("queue_launch"), "device");
    EXPECT_EQ(j.at("extras").at("queue_packets"), 0);
    EXPECT_EQ(j.at("extras").at("queue_shade"), "sort");
    EXPECT_TRUE(j.at("kernel_ms").contains("shade sorted")) << j.at("kernel_ms");
    EXPECT_EQ(j.at("max_launch_ms"), 0) << "the default cap gives way to device sizing";
    std::remove(out.c_str());
}

// --version names the commit the binary was built from (the one every result row records), and
// exits 0 without asking for a subcommand.
TEST(Cli, VersionNamesTheBuildCommit) {
    Result r = run("--version");
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out, std::string("rtlab ") + RTLAB_COMMIT + "\n");
    Result h = run("--help");
    EXPECT_NE(h.out.find("--version"), std::string::npos) << h.out;
}

TEST(Cli, PipelineHelpListsTheRegistry) {
    Result r = run("render --help");
    EXPECT_EQ(r.status, 0);
    for (const rt::PipelineInfo& p : rt::pipelineRegistry().all()) {
        EXPECT_NE(r.out.find(p.name + ": " + p.title), std::string::npos) << p.name << "\n"
                                                                          << r.out;
        // Each pipeline's own options are flags of every front end, with their help.
        for (const rt::PipelineOption& o : p.options) {
            EXPECT_NE(r.out.find(o.flag()), std::string::npos) << o.flag() << "\n" << r.out;
            EXPECT_NE(r.out.find(o.help.substr(0, 30)), std::string::npos) << o.help << "\n"
                                                                           << r.out;
        }
    }
    Result c = run("compare --help");
    for (const std::string& name : rt::pipelineRegistry().names(true))
        EXPECT_NE(c.out.find(name), std::string::npos) << name << "\n" << c.out;
}

// compare prints each pipeline's rays (counted in an untimed frame), Mrays/s and launches beside
// its times and errors: at least one primary ray a pixel, and at least one launch.
TEST(Cli, CompareShowsRaysRateAndLaunches) {
    Result r = run("compare scenes/shadows.json --size 32x18 --repeats 1");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("Mrays/s"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("launches"), std::string::npos) << r.out;
    for (const std::string& name : rt::pipelineRegistry().names(true)) {
        if (rt::pipelineRegistry().get(name).reference) continue;
        size_t at = r.out.find("\n" + name + " ");
        ASSERT_NE(at, std::string::npos) << name << "\n" << r.out;
        std::istringstream line(r.out.substr(at + 1, r.out.find('\n', at + 1) - at - 1));
        std::vector<std::string> cols;
        for (std::string c; line >> c;) cols.push_back(c);
        ASSERT_EQ(cols.size(), 9u) << line.str();
        EXPECT_GE(std::stoll(cols[6]), 32 * 18) << name << ": rays";  // primary rays at least
        EXPECT_GT(std::stod(cols[7]), 0.0) << name << ": Mrays/s";
        EXPECT_GE(std::stoi(cols[8]), 1) << name << ": launches";
    }
}

// rtlab predict: one JSON object a scene; a scene with nothing to hit gives every lane a one-ray
// tree, so all 32 are busy and one tree a work-item is predicted; the threshold decides the rest.
TEST(Cli, PredictSaysADesignPerScene) {
    auto predict = [](const std::string& threshold) {
        Result r =
            run("predict scenes/empty.json scenes/spheres.json --size 64x36 --warps 32 "
                "--json --threshold " +
                threshold);
        EXPECT_EQ(r.status, 0) << r.err;
        EXPECT_EQ(lines(r.out), 2) << r.out;
        std::vector<nlohmann::json> rows;
        std::istringstream in(r.out);
        for (std::string line; std::getline(in, line);) rows.push_back(nlohmann::json::parse(line));
        return rows;
    };
    const std::vector<nlohmann::json> strict = predict("32");
    ASSERT_EQ(strict.size(), 2u);
    const nlohmann::json& empty = strict[0];
    EXPECT_EQ(empty.at("busy_lanes").get<double>(), 32.0);
    EXPECT_EQ(empty.at("largest_tree"), 1);
    EXPECT_EQ(empty.at("rays_per_pixel").get<double>(), 1.0);
    EXPECT_EQ(empty.at("warps"), 32);
    EXPECT_EQ(empty.at("width"), 64);
    EXPECT_EQ(empty.at("predicted"), "tree-per-work-item");  // 32 is at the threshold, not below
    EXPECT_EQ(empty.at("commit"), RTLAB_COMMIT);             // what the figures came from
    EXPECT_EQ(empty.at("persist_schedule"), "nested");       // every lane busy, one object
    const nlohmann::json& spheres = strict[1];
    EXPECT_GT(spheres.at("largest_tree").get<int>(), 1);  // mirrors and glass branch
    EXPECT_LT(spheres.at("busy_lanes").get<double>(), 32.0);
    EXPECT_GT(spheres.at("rays_per_pixel").get<double>(), 1.0);
    EXPECT_EQ(spheres.at("predicted"), "queue");
    EXPECT_EQ(spheres.at("persist_schedule"), "regrouped");  // below 27.8 busy lanes
    const std::vector<nlohmann::json> lenient = predict("0");
    ASSERT_EQ(lenient.size(), 2u);
    EXPECT_EQ(lenient[1].at("predicted"), "tree-per-work-item");
    EXPECT_EQ(lenient[1].at("busy_lanes"), spheres.at("busy_lanes"));  // a fixed seed
    EXPECT_FALSE(spheres.contains("shading_keys"));  // asked for with --shading only

    // --shading: where every ray misses, one key a warp step in every order.
    Result r = run("predict scenes/empty.json --size 64x36 --warps 32 --json --shading");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json keys = nlohmann::json::parse(r.out).at("shading_keys");
    for (const char* order : {"megakernel", "bounce", "bounce_sorted"})
        EXPECT_EQ(keys.at(order).get<double>(), 1.0) << order;
    r = run("predict scenes/empty.json --size 64x36 --warps 32 --shading");
    EXPECT_NE(r.out.find("shading keys a warp step: megakernel 1.00, bounce loop 1.00"),
              std::string::npos)
        << r.out;
}

// A bad scene after good ones: the good ones' rows stay on stdout, the error is one line.
TEST(Cli, PredictStopsAtABadSceneWithOneLine) {
    Result r = run("predict scenes/empty.json scenes/nope.json --size 64x36 --warps 8 --json");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(lines(r.out), 1) << r.out;
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("scenes/nope.json: cannot open"), std::string::npos) << r.err;
}

// --stats prints ray counts and rays/s; --stats-json writes them for scripts.
TEST(Cli, StatsJsonCarriesTimesLaunchesAndRays) {
    const std::string json = rt::test::scratchPath("stats.json");
    const std::string png = rt::test::scratchPath("stats.png");
    Result r = run("render scenes/shadows.json --size 32x18 --pipeline mega --stats --stats-json " +
                   json + " -o " + png);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("rays primary"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("rays/s"), std::string::npos) << r.out;
    std::ifstream in(json);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    const nlohmann::json j = nlohmann::json::parse(text);
    EXPECT_EQ(j.at("rays").at("primary").get<long long>(), 32 * 18);
    EXPECT_GT(j.at("device_ms").get<double>(), 0);
    EXPECT_GE(j.at("launches").get<int>(), 1);
    EXPECT_EQ(j.at("pipeline"), "mega");
    // Every setting that decides the frame, and how its programs were obtained.
    EXPECT_EQ(j.at("aa"), 1);
    EXPECT_EQ(j.at("shadow_samples"), 16);  // scenes/shadows.json's render.shadow_samples
    EXPECT_EQ(j.at("layout"), "tree");
    EXPECT_TRUE(j.at("accel").is_string());
    const nlohmann::json& programs = j.at("programs");
    EXPECT_EQ(programs.at("built").get<int>() + programs.at("from_disk").get<int>() +
                  programs.at("in_memory").get<int>(),
              1)
        << programs;  // the megakernel is one program
    EXPECT_FALSE(j.at("buffers").contains("adaptive-AA centres")) << "allocated without --adaptive";
    std::remove(json.c_str());
    std::remove(png.c_str());
}

// --device gpu (or cpu) on a machine without one names what OpenCL sees instead.
TEST(Cli, DeviceTypeWithoutSuchDeviceSaysSo) {
    bool gpu = false;
    for (const rt::DeviceInfo& d : rt::listDevices()) gpu = gpu || d.isGpu();
    if (gpu) GTEST_SKIP() << "this machine has a GPU";
    Result r = run("render scenes/spheres.json --device gpu -o " + rt::test::scratchPath("g.png"));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("--device gpu: no GPU device found (OpenCL sees: "), std::string::npos)
        << r.err;
    EXPECT_EQ(lines(r.err), 1) << r.err;
}

// rtlab scenes and rtlab sweeps list what exists, a line each; the sweep help lists every sweep.
TEST(Cli, ScenesAndSweepsAreListed) {
    Result scenes = run("scenes");
    EXPECT_EQ(scenes.status, 0) << scenes.err;
    for (const auto& e : std::filesystem::directory_iterator("scenes"))
        if (e.path().extension() == ".json")
            EXPECT_NE(scenes.out.find("  " + e.path().stem().string() + " "), std::string::npos)
                << e.path() << "\n"
                << scenes.out;
    EXPECT_NE(scenes.out.find("Cornell box from triangles"), std::string::npos) << scenes.out;
    EXPECT_NE(scenes.out.find("divergence/: "), std::string::npos) << scenes.out;
    for (const char* spd : {"balls", "gears", "mount", "rings", "teapot", "tetra", "tree"})
        EXPECT_NE(scenes.out.find(std::string(" ") + spd + ".nff"), std::string::npos)
            << spd << "\n"
            << scenes.out;
    EXPECT_NE(scenes.out.find("spd/: 7 NFF scene(s)"), std::string::npos) << scenes.out;
    Result sweeps = run("sweeps");
    Result help = run("sweep --help");
    EXPECT_EQ(sweeps.status, 0) << sweeps.err;
    for (const auto& e : std::filesystem::directory_iterator("bench/sweeps")) {
        if (e.path().has_extension()) continue;  // README.md
        std::string name = e.path().filename().string();
        EXPECT_NE(sweeps.out.find("  " + name + " "), std::string::npos) << name << "\n"
                                                                         << sweeps.out;
        EXPECT_NE(help.out.find(" " + name + ": "), std::string::npos) << name << "\n" << help.out;
    }
    EXPECT_NE(sweeps.out.find("a first look at a device"), std::string::npos) << sweeps.out;
}

// A sweep does not overwrite results already in its output folder unless --force is given, and
// says so before measuring anything.
TEST(Cli, SweepKeepsEarlierResultsWithoutForce) {
    std::filesystem::path dir = rt::test::scratchPath("keep/");
    std::ofstream(dir / "one")
        << "repeats = 1\nwarmup = 0\ncount-rays = no\n[x]\nscenes = spheres\n"
           "pipelines = mega\nsizes = 8x6\nbounces = 0\n";
    std::string cmd =
        "sweep " + (dir / "one").string() + " --no-charts --out " + (dir / "o").string();
    Result first = run(cmd);
    ASSERT_EQ(first.status, 0) << first.err;
    std::ofstream(dir / "o" / "one.json", std::ios::app) << "kept";
    Result again = run(cmd);
    EXPECT_EQ(again.status, 1);
    EXPECT_NE(again.err.find("holds one results already"), std::string::npos) << again.err;
    EXPECT_EQ(lines(again.err), 1) << again.err;
    std::ifstream kept(dir / "o" / "one.json");
    std::string text((std::istreambuf_iterator<char>(kept)), {});
    EXPECT_NE(text.find("kept"), std::string::npos) << "the old file was overwritten";
    Result forced = run(cmd + " --force");
    EXPECT_EQ(forced.status, 0) << forced.err;
}

// --stats-json - writes the JSON, and nothing else, to standard output (no file named "-").
TEST(Cli, StatsJsonToStandardOutput) {
    std::filesystem::path dir = rt::test::scratchPath("stdout_json/");
    std::string cmd = "cd " + dir.string() + " && " + std::string(RTLAB_BIN_DIR) +
                      "/rtlab render " + std::string(RTLAB_SOURCE_DIR) +
                      "/scenes/spheres.json --size 16x12 --stats-json - -o " +
                      (dir / "x.png").string() + " 2>/dev/null";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    std::array<char, 4096> buf;
    while (size_t n = fread(buf.data(), 1, buf.size(), p)) out.append(buf.data(), n);
    EXPECT_EQ(pclose(p), 0);
    nlohmann::json j = nlohmann::json::parse(out, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << out;
    EXPECT_EQ(j.at("width"), 16);
    EXPECT_GE(j.at("rays").at("primary").get<long long>(), 16 * 12);
    EXPECT_FALSE(std::filesystem::exists(dir / "-"));
}

TEST(Cli, DevicesListsEveryDevice) {
    Result r = run("devices");
    EXPECT_EQ(r.status, 0);
    for (const rt::DeviceInfo& d : rt::listDevices())
        EXPECT_NE(r.out.find(d.name), std::string::npos) << d.name << " missing from\n" << r.out;
    EXPECT_NE(r.out.find("max allocation"), std::string::npos) << r.out;
    for (const rt::DeviceInfo& d : rt::listDevices())
        EXPECT_NE(
            r.out.find("at most " + std::to_string(d.maxWorkGroup) + " work-items a work-group"),
            std::string::npos)
            << r.out;
}

TEST(Cli, HelpExplainsEveryRenderFlag) {
    Result r = run("render --help");
    EXPECT_EQ(r.status, 0);
    for (const char* flag :
         {"--pipeline", "--device", "--size", "--bounces", "--shadow-samples", "--aa", "--stats",
          "--memory-budget", "--layout", "--kernel-dir", "--offset"})
        EXPECT_NE(r.out.find(flag), std::string::npos) << flag;
    // A pipeline's own option says its default as the shared flags do.
    EXPECT_NE(r.out.find("weighted (B*(C-1)+1 rays) [tree]"), std::string::npos) << r.out;
}

}  // namespace

// Shards of a sweep measured by rtlab-bench (as on the machines of an array job) merge through
// `rtlab sweep --import` into one set in the sweep's cell order, kept frames scored on the rows
// they belong to; one shard alone is imported as an incomplete set.
TEST(Cli, ShardsImportIntoOneSetInCellOrder) {
    std::string bench = std::string(RTLAB_BIN_DIR) + "/rtlab-bench";
    if (!std::filesystem::exists(bench)) GTEST_SKIP() << "rtlab-bench not built";
    std::filesystem::path dir = rt::test::scratchPath("shards/");
    std::ofstream(dir / "tiny")
        << "repeats = 1\nwarmup = 0\ncount-rays = no\n"
           "reference-bounces = 2\nreference-shadow-samples = 1\n"
           "reference-aa = 1\n"
           "[bounces]\nscenes = spheres cornell\npipelines = mega wave\n"
           "sizes = 16x12\nbounces = 1 2\n"
           "[accuracy]\nscenes = spheres\npipelines = queue\nsizes = 16x12\n"
           "bounces = 2\nimages = yes\n";
    for (int i = 0; i < 2; ++i) {
        std::string cmd = bench + " --sweep=" + (dir / "tiny").string() +
                          " --out=" + (dir / ("s" + std::to_string(i))).string() +
                          " --shard=" + std::to_string(i) + "/2 2>/dev/null";
        ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    }
    auto load = [&](const char* out) {
        std::ifstream f(dir / out / "tiny.json");
        return nlohmann::json::parse(f);
    };
    Result r = run("sweep " + (dir / "tiny").string() + " --import " + (dir / "s1").string() + " " +
                   (dir / "s0").string() + " --out " + (dir / "merged").string() + " --no-charts");
    ASSERT_EQ(r.status, 0) << r.err;
    nlohmann::json set = load("merged");
    ASSERT_EQ(set["rows"].size(), 9u);  // 2 scenes x 2 pipelines x 2 bounce limits, + 1
    for (size_t i = 0; i < 9; ++i) EXPECT_EQ(set["rows"][i]["cell_index"], i);
    EXPECT_EQ(set["rows"][8]["pipeline"], "queue");
    EXPECT_TRUE(set["rows"][8].contains("rmse"));  // its frame followed it
    for (size_t i = 0; i < 8; ++i) EXPECT_FALSE(set["rows"][i].contains("rmse")) << i;
    EXPECT_EQ(set["meta"]["shards"], nlohmann::json({"0/2", "1/2"}));
    EXPECT_EQ(set["meta"]["complete"], true);
    EXPECT_EQ(set["meta"]["cells"].get<double>(), 9);

    r = run("sweep " + (dir / "tiny").string() + " --import " + (dir / "s0").string() + " --out " +
            (dir / "half").string() + " --no-charts");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("1 of 2 shards imported"), std::string::npos) << r.err;
    EXPECT_EQ(load("half")["meta"]["complete"], false);
    std::filesystem::remove_all(dir);
}
