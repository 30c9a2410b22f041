// rtlab-view under Xvfb (Mesa's software OpenGL): the split view shows exactly what
// `rtlab render` writes for each pipeline, a failed reload keeps the old scene, and a missing
// display or a bad scene ends in one line and a non-zero exit instead of a crash.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <utility>

#include "image/compare.h"
#include "image/image_io.h"
#include "scratch_dir.h"

namespace {

namespace fs = std::filesystem;

const std::string kBin = RTLAB_BIN_DIR;
const std::string kXvfb = "xvfb-run -a -s \"-screen 0 1024x768x24\" ";

struct Result {
    int status;
    std::string out, err;
};

int exitStatus(int st) { return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st); }

std::string slurp(const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs a shell command; onFirstLine (if any) is called once the first stdout line arrives.
Result run(const std::string& cmd, const std::function<void()>& onFirstLine = {}) {
    // One stderr file per call and process: CTest runs the cases in parallel.
    static int calls = 0;
    std::string errFile = rt::test::scratchPath("err_" + std::to_string(++calls) + ".txt");
    Result r{};
    FILE* p = popen((cmd + " 2>" + errFile).c_str(), "r");
    std::array<char, 4096> line;
    bool first = true;
    while (fgets(line.data(), int(line.size()), p)) {
        r.out += line.data();
        if (first && r.out.back() == '\n') {
            first = false;
            if (onFirstLine) onFirstLine();
        }
    }
    r.status = exitStatus(pclose(p));
    r.err = slurp(errFile);
    return r;
}

int lines(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

// A folder inside this process's own scratch folder: CTest runs the cases in parallel, and two
// processes (or an earlier run's leftovers) must never share a file.
std::string privateDir(const std::string& name) { return rt::test::scratchPath(name + "/"); }

// Writes `text` into a FIFO as soon as a reader opens it, so that a reader sees exactly this text
// at its next open, whatever the speed of the device; gives up after two minutes (reader died).
bool feedFifo(const std::string& fifo, const std::string& text) {
    for (int attempt = 0; attempt < 12000; ++attempt) {
        int fd =
            open(fifo.c_str(), O_WRONLY | O_NONBLOCK);  // fails with ENXIO until a reader opens
        if (fd >= 0) {
            fcntl(fd, F_SETFL, 0);
            bool ok = write(fd, text.data(), text.size()) == ssize_t(text.size());
            close(fd);
            return ok;
        }
        usleep(10000);
    }
    return false;
}

bool haveXvfb() { return std::system("command -v xvfb-run >/dev/null 2>&1") == 0; }

rt::Image columns(const rt::Image& image, int x0, int x1) {
    rt::Image out(x1 - x0, image.height);
    for (int y = 0; y < image.height; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c) out.pixel(x - x0, y)[c] = image.pixel(x, y)[c];
    return out;
}

// One 8-bit sRGB step, in linear units, where the steps are widest (at white): compareImages
// works on linear values, and the pipelines agree to one PNG quantisation step.
double oneSrgbStep() {
    auto decode = [](double s) {
        return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
    };
    return decode(1.0) - decode(254.0 / 255.0) + 1e-6;
}

std::string renderPng(const std::string& scene, const std::string& pipeline) {
    std::string out =
        privateDir("render") + fs::path(scene).stem().string() + "_" + pipeline + ".png";
    Result r = run(kBin + "/rtlab render " + scene + " --pipeline " + pipeline + " -o " + out);
    EXPECT_EQ(r.status, 0) << r.err;
    return out;
}

void expectSame(const rt::Image& shot, const rt::Image& render, int x0, int x1, const char* side) {
    rt::ImageDiff d =
        rt::compareImages(columns(shot, x0, x1), columns(render, x0, x1), oneSrgbStep());
    EXPECT_EQ(d.pixelsOver, 0) << side << ": max difference " << d.maxAbs << " (linear)";
    EXPECT_LE(d.maxAbs, oneSrgbStep()) << side;
}

class Viewer : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!fs::exists(kBin + "/rtlab-view")) GTEST_SKIP() << "rtlab-view was not built";
        if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is missing (scripts/setup installs it)";
    }
};

TEST_F(Viewer, SplitViewHalvesMatchTheirPipelinesRenders) {
    const std::string scene = "scenes/spheres.json";
    std::string shotPath = privateDir("split") + "split.png";
    Result r = run(kXvfb + kBin + "/rtlab-view " + scene +
                   " --frames 30 --split --no-overlay --scale 1 --screenshot " + shotPath);
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    rt::Image shot = rt::readImage(shotPath);
    rt::Image mega = rt::readImage(renderPng(scene, "mega"));
    rt::Image wave = rt::readImage(renderPng(scene, "wave"));
    ASSERT_EQ(shot.width, mega.width);
    ASSERT_EQ(shot.height, mega.height);
    // The divider starts at 50%: columns left of it show the megakernel, the rest the wavefront.
    int divider = shot.width / 2;
    expectSame(shot, mega, 0, divider, "left (megakernel)");
    expectSame(shot, wave, divider, shot.width, "right (wavefront)");
}

TEST_F(Viewer, SplitPairPicksWhichPipelineIsOnWhichSide) {
    const std::string scene = "scenes/spheres.json";
    std::string shotPath = privateDir("split_pair") + "split.png";
    Result r =
        run(kXvfb + kBin + "/rtlab-view " + scene +
            " --frames 30 --split wave,mega --no-overlay --scale 1 --screenshot " + shotPath);
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("wave"), std::string::npos) << r.out;
    rt::Image shot = rt::readImage(shotPath);
    rt::Image mega = rt::readImage(renderPng(scene, "mega"));
    rt::Image wave = rt::readImage(renderPng(scene, "wave"));
    ASSERT_EQ(shot.width, wave.width);
    int divider = shot.width / 2;
    expectSame(shot, wave, 0, divider, "left (wavefront)");
    expectSame(shot, mega, divider, shot.width, "right (megakernel)");
}

TEST_F(Viewer, SceneErrorOnReloadKeepsTheOldSceneWithOneLine) {
    std::string dir = privateDir("reload");
    std::string scene = dir + "scene.json", shotPath = dir + "after.png";
    // The scene is a FIFO: the viewer's first read gets the good scene, and the reload at
    // frame 6 gets a broken one. Each open blocks until the other side is there, so the order
    // holds on a slow CPU and on a GPU that renders the six frames in milliseconds alike.
    ASSERT_EQ(mkfifo(scene.c_str(), 0600), 0) << scene << ": " << std::strerror(errno);
    std::thread good([&] { EXPECT_TRUE(feedFifo(scene, slurp("scenes/spheres.json"))); });
    std::thread broken;
    // The first stdout line comes after the scene was read and closed.
    Result r = run(
        kXvfb + kBin + "/rtlab-view " + scene +
            " --frames 10 --keys 6:R --no-overlay --scale 1 --screenshot " + shotPath,
        [&] { broken = std::thread([&] { EXPECT_TRUE(feedFifo(scene, "{\"spheres\": [\n")); }); });
    good.join();
    if (broken.joinable()) broken.join();
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("reload failed, kept the previous scene"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("scene.json"), std::string::npos) << r.err;
    rt::Image shot = rt::readImage(shotPath);
    rt::Image mega = rt::readImage(renderPng("scenes/spheres.json", "mega"));
    expectSame(shot, mega, 0, shot.width, "after the failed reload");
}

TEST_F(Viewer, AnimationMovesTheFirstSphereInBothPipelines) {
    // --animate orbits sphere 0 on a 48-point circle of radius 0.8 once every 6 s, and automation
    // advances the clock by 1/30 s per frame: frame 16 renders t = 0.5 s, exactly on point 4.
    const double angle = 2 * M_PI * 4 / 48;
    float x = -1.6f + 0.8f * float(std::cos(angle)), z = 7.f + 0.8f * float(std::sin(angle));
    std::string text = slurp("scenes/spheres.json");
    const std::string from = "{\"center\": [-1.6, 1.2, 7]";
    size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << "scenes/spheres.json changed; update this test";
    char moved[128];
    std::snprintf(moved, sizeof moved, "{\"center\": [%.9g, 1.2, %.9g]", x, z);
    std::string dir = privateDir("animate");
    std::ofstream(dir + "spheres.json") << text.replace(at, from.size(), moved);

    std::string shotPath = dir + "frame16.png";
    Result r = run(kXvfb + kBin + "/rtlab-view scenes/spheres.json --animate --frames 16 --split " +
                   "--no-overlay --scale 1 --screenshot " + shotPath);
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    rt::Image shot = rt::readImage(shotPath);
    rt::Image expected = rt::readImage(renderPng(dir + "spheres.json", "mega"));
    ASSERT_EQ(shot.width, expected.width);
    expectSame(shot, expected, 0, shot.width, "frame 16 of the orbit");
}

TEST_F(Viewer, SlowFrameComesInPiecesAndAKeyAtAPieceRestartsIt) {
    // 16-row pieces of a 240-row frame: 15 pieces. '+' pressed once piece 3 is on screen must
    // reach the render thread before the frame ends (the thread waits for each piece to be
    // shown), so the frame restarts with one bounce more, and --frames 1 ends on that frame.
    const std::string scene = "scenes/spheres.json";
    std::string shotPath = privateDir("pieces") + "shot.png";
    Result r = run(kXvfb + kBin + "/rtlab-view " + scene +
                   " --bounces 2 --piece-rows 16 --frames 1 --keys 1.3:+ --no-overlay --scale 1"
                   " --screenshot " +
                   shotPath);
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("the last in 15 pieces, 1 restarted"), std::string::npos) << r.out;
    std::string expected = privateDir("pieces") + "b3.png";
    Result render = run(kBin + "/rtlab render " + scene + " --bounces 3 -o " + expected);
    ASSERT_EQ(render.status, 0) << render.err;
    rt::Image shot = rt::readImage(shotPath);
    expectSame(shot, rt::readImage(expected), 0, shot.width, "the restarted frame, bounce limit 3");
}

TEST_F(Viewer, SplitViewOfMegaAndWaveComesInPieces) {
    // Both default halves render row windows (the tree wavefront too), so a slow split
    // frame comes in pieces like a single pipeline's: 16 rows of 240, 15 pieces, each half the
    // same as its pipeline's whole frame.
    const std::string scene = "scenes/spheres.json";
    std::string shotPath = privateDir("split_pieces") + "shot.png";
    Result r =
        run(kXvfb + kBin + "/rtlab-view " + scene +
            " --split --piece-rows 16 --frames 1 --no-overlay --scale 1 --screenshot " + shotPath);
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("the last in 15 pieces, 0 restarted"), std::string::npos) << r.out;
    rt::Image shot = rt::readImage(shotPath);
    rt::Image mega = rt::readImage(renderPng(scene, "mega"));
    rt::Image wave = rt::readImage(renderPng(scene, "wave"));
    ASSERT_EQ(shot.width, mega.width);
    const int divider = shot.width / 2;
    expectSame(shot, mega, 0, divider, "left (megakernel)");
    expectSame(shot, wave, divider, shot.width, "right (wavefront)");
}

TEST_F(Viewer, BruteForceOnABigMeshAsksFirst) {
    // The knot's 12,800 triangles x 320x240 pixels x 4 rays = 3.9e9 tests a frame. From wide, B
    // asks about none; M answers "skip" (to grid) and is used up; B, B reach wide again; B asks,
    // B confirms none; B asks about bv. --frames 1: the keys come after frame 1, so nothing
    // renders with brute force.
    Result r = run(kXvfb + kBin + "/rtlab-view scenes/models/knot.obj --accel wide --frames 1 " +
                   "--keys 1:BMBBBBB --no-overlay --scale 1");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    const std::string askNone = "accel none tests every ray against all 12800 triangles, 3.9e+09";
    size_t at = r.out.find(askNone);
    ASSERT_NE(at, std::string::npos) << r.out;
    for (const std::string& next : {std::string("skipped brute force, accel grid"), askNone,
                                    std::string("accel none, as confirmed"),
                                    std::string("accel bv tests every ray that enters a mesh's "
                                                "bounds against all its triangles (12800)")}) {
        at = r.out.find(next, at + 1);
        ASSERT_NE(at, std::string::npos) << "no '" << next << "' in order in:\n" << r.out;
    }
}

TEST_F(Viewer, BruteForceOnASmallSceneSwitchesAtOnce) {
    Result r = run(kXvfb + kBin + "/rtlab-view scenes/spheres.json --accel wide --frames 1 " +
                   "--keys 1:B --no-overlay --scale 1");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_EQ(r.out.find("press B again"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("accel none, as confirmed"), std::string::npos) << r.out;
}

TEST_F(Viewer, FirstLineNamesRenderAndWindowSizesAndScaleFitsTheScreen) {
    // Xvfb's screen is 1024x768: 320x240 doubles to 640x480, 800x600 would not fit doubled.
    Result small = run(kXvfb + kBin + "/rtlab-view scenes/spheres.json --frames 1 --no-overlay");
    ASSERT_EQ(small.status, 0) << small.out << small.err;
    EXPECT_NE(small.out.find("rendering 320x240, window 640x480 (--scale 2)"), std::string::npos)
        << small.out;
    Result large = run(kXvfb + kBin +
                       "/rtlab-view scenes/spheres.json --size 800x600 --frames 1 --no-overlay");
    ASSERT_EQ(large.status, 0) << large.out << large.err;
    EXPECT_NE(large.out.find("rendering 800x600, window 800x600 (--scale 1)"), std::string::npos)
        << large.out;
    // Xvfb has no high-DPI screen: the framebuffer is the window, and is not named.
    EXPECT_EQ(large.out.find("framebuffer"), std::string::npos) << large.out;
}

TEST(ViewerErrors, NoDisplayEndsInOneLine) {
    if (!fs::exists(kBin + "/rtlab-view")) GTEST_SKIP() << "rtlab-view was not built";
    Result r = run("env -u DISPLAY -u WAYLAND_DISPLAY " + kBin +
                   "/rtlab-view scenes/spheres.json --frames 1");
    EXPECT_NE(r.status, 0);
    EXPECT_LT(r.status, 128) << "crashed";
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("display"), std::string::npos) << r.err;
}

TEST(ViewerErrors, SplitPairOutsideTheRegistryEndsInOneLine) {
    if (!fs::exists(kBin + "/rtlab-view")) GTEST_SKIP() << "rtlab-view was not built";
    for (const char* pair : {"mega,nope", "mega", "cpu,mega"}) {
        Result r = run(kBin + "/rtlab-view scenes/spheres.json --split " + pair);
        EXPECT_NE(r.status, 0) << pair;
        EXPECT_LT(r.status, 128) << pair << ": crashed";
        EXPECT_EQ(lines(r.err), 1) << pair << ": " << r.err;
        EXPECT_NE(r.err.find("--split " + std::string(pair)), std::string::npos) << r.err;
    }
}

TEST(ViewerErrors, UnknownScriptedKeyEndsInOneLine) {
    if (!fs::exists(kBin + "/rtlab-view")) GTEST_SKIP() << "rtlab-view was not built";
    Result r = run(kBin + "/rtlab-view scenes/spheres.json --keys 2:Z");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("--keys 2:Z: no control on 'Z'"), std::string::npos) << r.err;
}

TEST(ViewerErrors, BadPieceInScriptOrPieceRowsEndsInOneLine) {
    if (!fs::exists(kBin + "/rtlab-view")) GTEST_SKIP() << "rtlab-view was not built";
    const std::pair<std::string, std::string> cases[] = {
        {"--keys 1.0:B", "--keys 1.0:B: expected FRAME:KEYS or FRAME.PIECE:KEYS"},
        {"--keys 1.x:B", "--keys 1.x:B: expected FRAME:KEYS or FRAME.PIECE:KEYS"},
        {"--piece-rows -3", "--piece-rows -3: must be >= 0"},
    };
    for (const auto& [flags, message] : cases) {
        Result r = run(kBin + "/rtlab-view scenes/spheres.json " + flags);
        EXPECT_EQ(r.status, 1) << flags;
        EXPECT_EQ(lines(r.err), 1) << flags << ": " << r.err;
        EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    }
}

TEST(ViewerErrors, BadSceneEndsInOneLine) {
    if (!fs::exists(kBin + "/rtlab-view")) GTEST_SKIP() << "rtlab-view was not built";
    Result r = run(kBin + "/rtlab-view scenes/no-such-scene.json");
    EXPECT_NE(r.status, 0);
    EXPECT_LT(r.status, 128) << "crashed";
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("no-such-scene.json"), std::string::npos) << r.err;
}

}  // namespace
