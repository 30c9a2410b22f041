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

struct AppConfig {
    bool overlay = true;
    long long frames = 0;    // automation: stop after this many frames (0 = interactive)
    std::string screenshot;  // automation: save the window here after the last frame
    // Automation: keys pressed once a frame count is shown, in frame order (see parseKeyScript).
    std::vector<std::pair<long long, int>> keys;
    float speed = 2.f;       // camera speed, scene units per second
    std::string framePath;   // how frames reach the texture, for the overlay
    bool animate = false;
};

// Parses "6:R" or "3:V 5:B+ 8:P": after frame 3 press V, after frame 5 press B then '+', ...
// Keys: the letters of the controls, '+' and '-'. Throws rt::Error naming --keys.
std::vector<std::pair<long long, int>> parseKeyScript(const std::string& script);

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
    double fps() const;

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
};

}  // namespace rt::view
