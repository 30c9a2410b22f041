// rtlab-view — the window thread: keyboard and mouse, the camera, the split divider, the overlay,
// screenshots, and the automation run (--frames N --screenshot F). Frames come from the render
// thread (viewer_renderer.h) and are shown through viewer_gl.h.
#pragma once

#include <chrono>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "apps/viewer_gl.h"
#include "apps/viewer_renderer.h"

struct GLFWwindow;

namespace rt::view {

// A scripted key press: once frame `frame` is shown complete, or, with piece > 0, once that
// frame's piece `piece` is shown (a slow frame comes in pieces).
struct ScriptedKey {
    long long frame = 0;
    int piece = 0;
    int key = 0;
};

struct AppConfig {
    bool overlay = true;
    long long frames = 0;    // automation: stop after this many frames (0 = interactive)
    std::string screenshot;  // automation: save the window here after the last frame
    // Automation: keys pressed once a frame (or piece) is shown, in order (see parseKeyScript).
    std::vector<ScriptedKey> keys;
    size_t triangles = 0;   // in the scene at start (the brute-force guard before a frame)
    long long pixels = 0;   // rendered pixels per frame, the same
    float speed = 2.f;      // camera speed, scene units per second
    std::string framePath;  // how frames reach the texture, for the overlay
    bool animate = false;
};

// Parses "6:R" or "3:V 5:B+ 8:P": after frame 3 press V, after frame 5 press B then '+', ...;
// "2.3:B" presses B once piece 3 of frame 2 is shown, before that frame is complete.
// Keys: the letters of the controls, '+' and '-'. Throws rt::Error naming --keys.
std::vector<ScriptedKey> parseKeyScript(const std::string& script);

// Brute force: --accel none tests every ray against every triangle, and bv every ray that
// enters a mesh's bounds against all of that mesh's triangles (nearly the same for one big mesh,
// whose bounds most rays enter: either way a frame of the bunny takes far too long for a window
// on a CPU device).
bool isBruteForce(RenderOptions::Accel accel);
// Ray-triangle tests a brute-force frame makes at the least: triangles x pixels x AA samples x
// (1 + bounce limit), one ray per bounce (shadow rays and glass's second ray come on top). Past
// kBruteForceTests (a few seconds a frame on a CPU device; the bunny at 320x240, B 3: 2.1e10),
// B asks before it switches to none or bv.
double bruteForceTests(size_t triangles, long long pixels, int aa, int bounces);
constexpr double kBruteForceTests = 1e9;

class App {
  public:
    App(GLFWwindow* window, GlDisplay& display, Renderer& renderer, ViewRequest first,
        AppConfig config);
    // Returns the exit status; throws rt::Error for a failure that ends the viewer.
    int run();

    // GLFW callbacks (static trampolines find the App through the window's user pointer).
    void onKey(int key);
    void onMouseButton(int button, int action);
    void onCursor(double x, double y);

  private:
    void send();
    void moveCamera(double dt);
    void receive();
    void draw();
    void saveScreenshot(const std::string& path);
    void message(const std::string& text);
    void cycleAccel();
    double fps() const;
    long long framesShown() const;  // complete frames shown so far

    GLFWwindow* window_;
    GlDisplay& display_;
    Renderer& renderer_;
    ViewRequest req_;
    AppConfig config_;

    FrameOut frame_;  // the frame on screen (its pixels already uploaded)
    bool haveFrame_ = false;
    uint64_t sceneGeneration_ = 0;
    // When frames arrived, with their index (the window may skip frames the device finished
    // between two wake-ups), for the FPS.
    std::deque<std::pair<std::chrono::steady_clock::time_point, uint64_t>> arrivals_;
    std::pair<std::chrono::steady_clock::time_point, uint64_t> firstArrival_{};

    float divider_ = 0.5f;
    enum class Drag { None, View, Divider } drag_ = Drag::None;
    double cursorX_ = 0, cursorY_ = 0;
    bool showStats_, showHelp_ = false;
    struct Message {
        std::string text;
        std::chrono::steady_clock::time_point until;
    };
    std::deque<Message> messages_;
    int labelSize_[2] = {0, 0};  // the split view's side labels, in texels
    int screenshots_ = 0;
    std::string fatal_;
    bool confirming_ = false;  // B asked whether to switch to brute force: B again says yes
};

}  // namespace rt::view
