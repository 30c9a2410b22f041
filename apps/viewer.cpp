// rtlab-view SCENE — a real-time window on the registered pipelines: one at a time (M cycles), or
// any two side by side (--split LEFT,RIGHT). Sets up GLFW (OpenGL 3.3 core), the OpenCL device and
// the render thread, then hands over to App (viewer_app.h). Every failure ends in one line on
// stderr
// ("rtlab-view: <reason>") and exit status 1, usage errors included.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "apps/options.h"
#include "apps/viewer_app.h"
#include "apps/viewer_gl.h"
#include "apps/viewer_overlay.h"
#include "apps/viewer_renderer.h"
#include "cli/parse_error.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "core/version.h"
#include "image/image_io.h"
#include "pipelines/registry.h"

namespace {

using namespace rt;

struct Args {
    std::string scene, pipeline, screenshot;  // pipeline: the registry's first by default
    cli::SceneFlags flags;
    int scale = 0;                    // 0: 2 when the window then fits the screen, else 1
    int pieceRows = 0;                // --piece-rows
    std::array<std::string, 2> pair;  // --split LEFT,RIGHT
    bool split = false, noOverlay = false, animate = false, noRayCount = false;
    long long frames = 0;
    std::string keys;
    float speed = 2.f, orbitRadius = 0.8f;
    double orbitPeriod = 6;
};

std::string lastGlfwError;

// Owns glfwInit/glfwTerminate; throws with GLFW's reason when there is no display.
struct GlfwSession {
    GlfwSession() {
        glfwSetErrorCallback([](int, const char* text) { lastGlfwError = text ? text : ""; });
        if (!glfwInit())
            throw Error(
                "no display: " + (lastGlfwError.empty() ? "glfwInit failed" : lastGlfwError) +
                " (run in a desktop session, or headless under xvfb-run -a)");
    }
    ~GlfwSession() { glfwTerminate(); }
};

struct Window {
    GLFWwindow* handle;
    Window(int width, int height, const std::string& title) {
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        handle = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!handle)
            throw Error("cannot open a " + std::to_string(width) + "x" + std::to_string(height) +
                        " window with OpenGL 3.3 core: " + lastGlfwError);
        glfwMakeContextCurrent(handle);
        glfwSwapInterval(1);
    }
    ~Window() { glfwDestroyWindow(handle); }
};

// The frame reaches the texture through the host; report 3.1's direct path would need the
// device to share GL objects, and the pipelines to render into a shared image.
std::string framePath(const ClContext& cl) {
    std::string ext = cl.device().device.getInfo<CL_DEVICE_EXTENSIONS>();
    if (ext.find("cl_khr_gl_sharing") == std::string::npos)
        return "host copy (no cl_khr_gl_sharing)";
    return "host copy (cl_khr_gl_sharing unused)";
}

// Whether a window of this many screen coordinates fits the primary monitor's current mode.
bool fits(int width, int height) {
    GLFWmonitor* monitor = glfwGetPrimaryMonitor();
    const GLFWvidmode* mode = monitor ? glfwGetVideoMode(monitor) : nullptr;
    return !mode || (width <= mode->width && height <= mode->height);
}

// "rendering 1280x720, window 1280x720 (--scale 1)", plus the framebuffer when a high-DPI
// screen makes it larger than the window: the frame is rendered at --size whatever the window,
// and drawn scaled to fill the framebuffer.
std::string windowSizes(GLFWwindow* window, const RenderOptions& o, int scale) {
    int ww = 0, wh = 0, fw = 0, fh = 0;
    glfwGetWindowSize(window, &ww, &wh);
    glfwGetFramebufferSize(window, &fw, &fh);
    char buf[256];
    int n = std::snprintf(buf, sizeof buf, "rendering %dx%d, window %dx%d (--scale %d)", o.width,
                          o.height, ww, wh, scale);
    if ((fw != ww || fh != wh) && n > 0) {
        float sx = 1, sy = 1;
        glfwGetWindowContentScale(window, &sx, &sy);
        std::snprintf(buf + n, sizeof buf - size_t(n),
                      ", framebuffer %dx%d (content scale %g: a high-DPI screen; the frame is "
                      "scaled up to it, not rendered at it)",
                      fw, fh, double(sx));
    }
    return buf;
}

int runViewer(Args& a) {
    Scene scene = loadScene(a.scene, readImage);
    for (const std::string& note : scene.notes)
        std::fprintf(stderr, "rtlab-view: note: %s\n", note.c_str());
    RenderOptions options = a.flags.apply(scene.defaults);
    if (!a.screenshot.empty()) {
        try {
            cli::checkOutputPath(a.screenshot);
        } catch (const Error& e) {
            std::string m = e.what();
            throw Error("--screenshot" + m.substr(m.find(' ')));
        }
        if (a.frames == 0) a.frames = 1;
    }
    auto keys = view::parseKeyScript(a.keys);
    if (a.frames < 0) throw Error("--frames " + std::to_string(a.frames) + ": must be >= 0");
    if (a.scale != 0 && (a.scale < 1 || a.scale > 8))
        throw Error("--scale " + std::to_string(a.scale) + ": must be in 1..8");
    if (a.pieceRows < 0)
        throw Error("--piece-rows " + std::to_string(a.pieceRows) + ": must be >= 0");

    GlfwSession glfw;
    if (a.scale == 0) a.scale = fits(options.width * 2, options.height * 2) ? 2 : 1;
    Window window(options.width * a.scale, options.height * a.scale, "rtlab-view " + scene.name);
    std::string sizes = windowSizes(window.handle, options, a.scale);
    view::GlDisplay display;
    display.warmUp();
    ClContext cl(selectDevice(a.flags.device), a.flags.kernelSources());
    std::string path = framePath(cl);
    std::printf("rtlab-view: %s on %s, %s, frames by %s; press H for help\n", scene.name.c_str(),
                cl.device().label().c_str(), sizes.c_str(), path.c_str());
    std::fflush(stdout);

    view::Renderer::Config rc;
    rc.scenePath = a.scene;
    rc.flags = a.flags;
    rc.animate = a.animate;
    rc.orbitRadius = a.orbitRadius;
    rc.orbitPeriod = a.orbitPeriod;
    rc.countRays = !a.noRayCount;
    rc.frameLimit = a.frames;
    rc.fixedStep = a.frames > 0 ? 1.0 / 30 : 0;
    rc.pieceRows = a.pieceRows;
    view::ViewRequest first;
    first.camera = scene.camera;
    first.split = a.split;
    first.pipeline = a.pipeline;
    first.pair = a.pair;
    first.bounces = options.bounces;
    first.accel = options.accel;
    const size_t triangles = scene.triangles.size();
    view::Renderer renderer(cl, std::move(scene), rc, [] { glfwPostEmptyEvent(); });

    view::AppConfig ac;
    ac.overlay = !a.noOverlay;
    ac.frames = a.frames;
    ac.screenshot = a.screenshot;
    ac.keys = keys;
    ac.speed = a.speed;
    ac.framePath = path;
    ac.animate = a.animate;
    ac.triangles = triangles;
    ac.pixels = (long long)(options.width) * options.height;
    view::App app(window.handle, display, renderer, first, ac);
    renderer.start(first);
    return app.run();
}

}  // namespace

// "--split LEFT,RIGHT": two registered device pipelines (they may be the same one).
std::array<std::string, 2> parsePair(const std::string& text,
                                     const std::vector<std::string>& names) {
    size_t comma = text.find(',');
    std::array<std::string, 2> pair = {text.substr(0, comma),
                                       comma == std::string::npos ? "" : text.substr(comma + 1)};
    for (const std::string& p : pair)
        if (std::find(names.begin(), names.end(), p) == names.end())
            throw Error("--split " + text + ": expected LEFT,RIGHT, each one of " +
                        pipelineRegistry().joinedNames(true));
    return pair;
}

int main(int argc, char** argv) {
    std::string keys = "\nKeys:\n";
    for (const std::string& line : view::helpLines()) keys += "  " + line + "\n";
    char guard[512];
    std::snprintf(guard, sizeof guard,
                  "\nSlow frames come in pieces of rows (about 100 ms each), shown as they finish "
                  "with a progress line in the overlay; a key that changes the view, or a "
                  "camera move, restarts the frame. B asks before it switches to brute force "
                  "(accel none, or bv, which bounds whole meshes only) when a frame would need "
                  "more than %.0e ray-triangle tests (triangles x pixels x AA samples x (1 + "
                  "bounce limit)): B again switches, any other key skips to grid.\n",
                  view::kBruteForceTests);
    keys += guard;
    CLI::App app{"rtlab-view: watch the pipelines render a scene in real time."};
    app.footer(keys);
    app.set_version_flag("--version", std::string("rtlab-view ") + RTLAB_COMMIT,
                         "Print the commit this binary was built from and exit");
    Args a;
    app.add_option("scene", a.scene,
                   "Scene file (.json or .nff) or model (.obj, .gltf, .glb, .ply)")
        ->required();
    const PipelineRegistry& registry = pipelineRegistry();
    const std::vector<std::string> names = registry.names(true);
    a.pipeline = names.at(0);
    a.pair = {names.at(0), names.at(names.size() > 1 ? 1 : 0)};
    cli::addPipelineOption(app, a.pipeline, false);
    std::string pair;
    CLI::Option* split =
        app.add_option("--split", pair,
                       "Start in split view; LEFT,RIGHT picks any two pipelines (" +
                           registry.joinedNames(true) + ") [" + a.pair[0] + "," + a.pair[1] + "]");
    split->expected(0, 1);
    app.add_option("--scale", a.scale,
                   "Window pixels (screen coordinates) per rendered pixel, 1..8 [2 when the "
                   "window then fits the screen, else 1]. The frame is always rendered at --size; "
                   "a high-DPI screen "
                   "gives the window a larger framebuffer (the first line says so), and the "
                   "frame is scaled up to fill it");
    app.add_option("--piece-rows", a.pieceRows,
                   "Render each frame in pieces of this many rows (automation, tests); 0, the "
                   "default, sizes pieces to take about 100 ms each, so a slow frame shows row "
                   "by row and a key or camera move restarts it");
    app.add_flag("--no-overlay", a.noOverlay,
                 "Hide the overlay and the split divider (O shows them)");
    app.add_flag("--animate", a.animate,
                 "Move the first sphere around a circle (until scene files carry 'animate')");
    app.add_option("--orbit-radius", a.orbitRadius, "--animate: circle radius")
        ->capture_default_str();
    app.add_option("--orbit-period", a.orbitPeriod, "--animate: seconds per turn")
        ->capture_default_str();
    app.add_option("--speed", a.speed, "Camera speed in scene units per second")
        ->capture_default_str();
    app.add_flag("--no-ray-count", a.noRayCount,
                 "Do not count rays on the device (no Mrays/s, slightly faster kernels)");
    app.add_option("--frames", a.frames,
                   "Render this many frames, then exit (automation); 0, the default, runs until "
                   "the window is closed");
    app.add_option("--screenshot", a.screenshot,
                   "After the last frame, save the window to this image (implies --frames 1)");
    app.add_option("--keys", a.keys,
                   "Automation: press keys once a number of frames is shown, e.g. \"6:R\" or "
                   "\"3:V 5:B+ 8:P\" (the control letters, + and -); \"2.3:B\" presses B once "
                   "piece 3 of frame 2 is shown");
    a.flags.add(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return cli::reportParseError(app, e, "rtlab-view", argc, argv);
    }
    try {
        a.split = split->count() > 0;
        if (!pair.empty()) a.pair = parsePair(pair, names);
        return runViewer(a);
    } catch (const Error& e) {
        std::fprintf(stderr, "rtlab-view: %s\n", e.what());
    } catch (const cl::Error& e) {
        std::fprintf(stderr, "rtlab-view: OpenCL error in %s: %s\n", e.what(),
                     clErrorName(e.err()));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtlab-view: unexpected error: %s\n", e.what());
    }
    return 1;
}
