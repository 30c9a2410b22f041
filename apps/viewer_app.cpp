// rtlab-view — the window thread's loop. It sleeps in glfwWaitEventsTimeout until input arrives or
// the render thread posts a finished frame, so it costs nothing while the device works.
#include "apps/viewer_app.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "apps/viewer_overlay.h"
#include "apps/viewer_srgb.h"
#include "core/accel.h"
#include "core/error.h"
#include "image/image_io.h"
#include "pipelines/registry.h"

namespace rt::view {
namespace {

using Clock = std::chrono::steady_clock;

App* self(GLFWwindow* w) { return static_cast<App*>(glfwGetWindowUserPointer(w)); }

bool sameCamera(const dev::Camera& a, const dev::Camera& b) {
    return a.position.x == b.position.x && a.position.y == b.position.y &&
           a.position.z == b.position.z && a.yaw == b.yaw && a.pitch == b.pitch && a.fovY == b.fovY;
}

constexpr float kTurnPerPixel = 0.004f;  // radians
constexpr float kMaxPitch = 1.55f;       // just short of straight up or down

}  // namespace

bool isBruteForce(RenderOptions::Accel accel) {
    return accel == RenderOptions::Accel::None || accel == RenderOptions::Accel::Bv;
}

double bruteForceTests(size_t triangles, long long pixels, int aa, int bounces) {
    return double(triangles) * double(pixels) * double(aa) * double(aa) * double(1 + bounces);
}

std::vector<ScriptedKey> parseKeyScript(const std::string& script) {
    std::vector<ScriptedKey> keys;
    std::string item;
    auto flush = [&] {
        if (item.empty()) return;
        size_t colon = item.find(':');
        long long frame = -1, piece = 0;
        try {
            if (colon != std::string::npos) {
                std::string at = item.substr(0, colon);
                size_t dot = at.find('.'), used = 0;
                frame = std::stoll(at.substr(0, dot), &used);
                if (used != std::min(dot, at.size())) frame = -1;
                if (dot != std::string::npos) {
                    piece = std::stoll(at.substr(dot + 1), &used);
                    if (used != at.size() - dot - 1 || piece < 1) frame = -1;
                }
            }
        } catch (const std::exception&) {
            frame = -1;
        }
        if (frame < 1 || colon + 1 >= item.size())
            throw Error("--keys " + item + ": expected FRAME:KEYS or FRAME.PIECE:KEYS, e.g. 6:R");
        for (char c : item.substr(colon + 1)) {
            char u = char(std::toupper((unsigned char)c));
            int key = u >= 'A' && u <= 'Z' ? GLFW_KEY_A + (u - 'A')
                      : u == '+'           ? GLFW_KEY_EQUAL
                      : u == '-'           ? GLFW_KEY_MINUS
                                           : -1;
            // Only keys with a press action can be scripted (W A S D Q E move while held).
            static const std::string kScriptable = "MVBRPHO+-";
            if (key < 0 || kScriptable.find(u) == std::string::npos)
                throw Error(std::string("--keys ") + item + ": no control on '" + c +
                            "' (scriptable keys: M V B R P H O + -)");
            keys.push_back({frame, int(piece), key});
        }
        item.clear();
    };
    for (char c : script) {
        if (c == ' ' || c == ',')
            flush();
        else
            item += c;
    }
    flush();
    // By when they are pressed: piece p of frame f comes before frame f is complete.
    auto when = [](const ScriptedKey& k) {
        return std::pair(k.frame, k.piece > 0 ? k.piece : std::numeric_limits<int>::max());
    };
    std::stable_sort(keys.begin(), keys.end(),
                     [&](const auto& a, const auto& b) { return when(a) < when(b); });
    return keys;
}

App::App(GLFWwindow* window, GlDisplay& display, Renderer& renderer, ViewRequest first,
         AppConfig config)
    : window_(window),
      display_(display),
      renderer_(renderer),
      req_(first),
      config_(std::move(config)),
      showStats_(config_.overlay) {
    glfwSetWindowUserPointer(window_, this);
    glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int) {
        if (action != GLFW_RELEASE) self(w)->onKey(key);
    });
    glfwSetMouseButtonCallback(window_, [](GLFWwindow* w, int button, int action, int) {
        self(w)->onMouseButton(button, action);
    });
    glfwSetCursorPosCallback(window_,
                             [](GLFWwindow* w, double x, double y) { self(w)->onCursor(x, y); });
    // The split view's pair is fixed for the session (--split LEFT,RIGHT): label it once, by the
    // registry's titles, both labels as wide as the longer.
    std::string labels[2] = {pipelineInfo(req_.pair[0]).title, pipelineInfo(req_.pair[1]).title};
    int width = int(std::max(labels[0].size(), labels[1].size()));
    for (int i = 0; i < 2; ++i) {
        TextCanvas label(width, 1, {0, 0, 0, 150});
        label.text(0, 0, labels[i], {255, 255, 255, 255});
        display_.uploadOverlay(1 + i, label.rgba(), label.width(), label.height());
        labelSize_[0] = label.width();
        labelSize_[1] = label.height();
    }
}

void App::send() { renderer_.request(req_); }

void App::message(const std::string& text) {
    messages_.push_back({text, Clock::now() + std::chrono::seconds(8)});
    while (messages_.size() > 4) messages_.pop_front();
}

void App::cycleAccel() {
    using Accel = RenderOptions::Accel;
    const Accel next = Accel((int(req_.accel) + 1) % 5);
    if (isBruteForce(next) && !confirming_) {
        size_t triangles = haveFrame_ ? frame_.triangles : config_.triangles;
        long long pixels = haveFrame_ ? (long long)(frame_.width) * frame_.height : config_.pixels;
        int aa = haveFrame_ ? frame_.options.aa : 1;
        double tests = bruteForceTests(triangles, pixels, aa, req_.bounces);
        if (tests > kBruteForceTests) {
            char text[320];
            std::snprintf(text, sizeof text,
                          next == Accel::None
                              ? "accel none tests every ray against all %zu triangles, %.1e tests "
                                "a frame: press B again to use it, any other key to skip to grid"
                              : "accel bv tests every ray that enters a mesh's bounds against all "
                                "its triangles (%zu), up to %.1e tests a frame: press B again to "
                                "use it, any other key to skip to grid",
                          triangles, tests);
            message(text);
            std::printf("rtlab-view: %s\n", text);
            std::fflush(stdout);
            confirming_ = true;
            return;
        }
    }
    if (confirming_) std::printf("rtlab-view: accel %s, as confirmed\n", accelName(next));
    confirming_ = false;
    req_.accel = next;
    message(std::string("accel ") + accelName(req_.accel));
    send();
}

void App::onKey(int key) {
    if (confirming_ && key != GLFW_KEY_B) {
        // The answer to "press B again": any other key skips brute force (none and bv, which
        // bounds whole meshes only) for the grid, and is used up by it.
        confirming_ = false;
        req_.accel = RenderOptions::Accel::Grid;
        message("skipped brute force: accel grid");
        std::printf("rtlab-view: skipped brute force, accel grid\n");
        std::fflush(stdout);
        send();
        return;
    }
    const std::string shown = pipelineInfo(req_.pipeline).title;
    switch (key) {
        case GLFW_KEY_ESCAPE:
            glfwSetWindowShouldClose(window_, GLFW_TRUE);
            return;
        case GLFW_KEY_M: {
            // Cycles through every registered device pipeline, in registry order.
            std::vector<std::string> names = pipelineRegistry().names(true);
            auto at = std::find(names.begin(), names.end(), req_.pipeline);
            req_.pipeline = at == names.end() || at + 1 == names.end() ? names.front() : *(at + 1);
            req_.split = false;
            message("showing the " + pipelineInfo(req_.pipeline).title);
            break;
        }
        case GLFW_KEY_V:
            req_.split = !req_.split;
            message(req_.split ? "split: " + pipelineInfo(req_.pair[0]).title + " left, " +
                                     pipelineInfo(req_.pair[1]).title + " right"
                               : "showing the " + shown);
            break;
        case GLFW_KEY_EQUAL:
        case GLFW_KEY_KP_ADD:
            if (req_.bounces >= RT_MAX_BOUNCE_LIMIT)
                return message("bounce limit is at its maximum, " +
                               std::to_string(RT_MAX_BOUNCE_LIMIT));
            ++req_.bounces;
            break;
        case GLFW_KEY_MINUS:
        case GLFW_KEY_KP_SUBTRACT:
            if (req_.bounces <= 0) return message("bounce limit is already 0");
            --req_.bounces;
            break;
        case GLFW_KEY_B:
            cycleAccel();
            return;
        case GLFW_KEY_R:
            ++req_.reloads;
            message("reloading the scene");
            break;
        case GLFW_KEY_P: {
            std::string name;
            do {
                char buf[256];
                std::snprintf(buf, sizeof buf, "rtlab-view-%s-%03d.png",
                              haveFrame_ ? frame_.sceneName.c_str() : "frame", ++screenshots_);
                name = buf;
            } while (std::filesystem::exists(name));
            try {
                saveScreenshot(name);
                message("saved " + name);
                std::printf("rtlab-view: saved %s\n", name.c_str());
            } catch (const std::exception& e) {
                message(e.what());
                std::fprintf(stderr, "rtlab-view: %s\n", e.what());
            }
            return;
        }
        case GLFW_KEY_H:
            showHelp_ = !showHelp_;
            return;
        case GLFW_KEY_O:
            showStats_ = !showStats_;
            return;
        default:
            return;
    }
    send();
}

void App::onMouseButton(int button, int action) {
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    if (action == GLFW_RELEASE) {
        drag_ = Drag::None;
        return;
    }
    int w = 0, h = 0;
    glfwGetWindowSize(window_, &w, &h);
    glfwGetCursorPos(window_, &cursorX_, &cursorY_);
    bool onDivider = req_.split && std::abs(cursorX_ - divider_ * w) <= 6;
    drag_ = onDivider ? Drag::Divider : Drag::View;
}

void App::onCursor(double x, double y) {
    double dx = x - cursorX_, dy = y - cursorY_;
    cursorX_ = x;
    cursorY_ = y;
    if (drag_ == Drag::Divider) {
        int w = 0, h = 0;
        glfwGetWindowSize(window_, &w, &h);
        if (w > 0) divider_ = std::clamp(float(x / w), 0.f, 1.f);
    } else if (drag_ == Drag::View) {
        req_.camera.yaw += float(dx) * kTurnPerPixel;
        req_.camera.pitch =
            std::clamp(req_.camera.pitch - float(dy) * kTurnPerPixel, -kMaxPitch, kMaxPitch);
        send();
    }
}

void App::moveCamera(double dt) {
    // The camera's axes as core/cl/camera.cl builds them: yaw about +y, then pitch.
    float cy = std::cos(req_.camera.yaw), sy = std::sin(req_.camera.yaw);
    float cp = std::cos(req_.camera.pitch), sp = std::sin(req_.camera.pitch);
    float forward[3] = {cp * sy, sp, cp * cy}, right[3] = {cy, 0, -sy};
    auto down = [&](int key) { return glfwGetKey(window_, key) == GLFW_PRESS ? 1.f : 0.f; };
    float f = down(GLFW_KEY_W) - down(GLFW_KEY_S), r = down(GLFW_KEY_D) - down(GLFW_KEY_A),
          u = down(GLFW_KEY_E) - down(GLFW_KEY_Q);
    if (f == 0 && r == 0 && u == 0) return;
    bool fast = down(GLFW_KEY_LEFT_SHIFT) + down(GLFW_KEY_RIGHT_SHIFT) > 0;
    float step = float(std::min(dt, 0.1)) * config_.speed * (fast ? 4.f : 1.f);
    req_.camera.position.x += step * (f * forward[0] + r * right[0]);
    req_.camera.position.y += step * (f * forward[1] + u);
    req_.camera.position.z += step * (f * forward[2] + r * right[2]);
    send();
}

void App::receive() {
    for (Notice& n : renderer_.takeNotices()) {
        std::fprintf(stderr, "rtlab-view: %s\n", n.text.c_str());
        if (n.fatal) fatal_ = n.text;
        message(n.text);
        if (n.reverted) {
            req_.bounces = n.bounces;
            req_.accel = n.accel;
            send();
        }
    }
    FrameOut f;
    if (!renderer_.takeFrame(f)) return;
    if (f.complete()) {  // FPS counts whole frames; pieces of a slow one only update the image
        arrivals_.emplace_back(Clock::now(), f.index);
        if (firstArrival_.second == 0) firstArrival_ = arrivals_.back();
        while (arrivals_.size() > 20) arrivals_.pop_front();
    }
    display_.uploadFrame(0, f.pipelines[0].rgb, f.width, f.height);
    if (f.pipelines.size() > 1) display_.uploadFrame(1, f.pipelines[1].rgb, f.width, f.height);
    for (PipelineFrame& p : f.pipelines) p.rgb = {};  // on the GPU now
    if (haveFrame_ && f.sceneGeneration != sceneGeneration_) {
        message("reloaded " + f.sceneName);
        std::printf("rtlab-view: reloaded %s\n", f.sceneName.c_str());
        // Follow the file's camera only when the edit changed it.
        if (!sameCamera(f.sceneCamera, frame_.sceneCamera)) {
            req_.camera = f.sceneCamera;
            send();
        }
    }
    sceneGeneration_ = f.sceneGeneration;
    frame_ = std::move(f);
    haveFrame_ = true;
}

long long App::framesShown() const {
    if (!haveFrame_) return 0;
    return (long long)frame_.index - (frame_.complete() ? 0 : 1);
}

double App::fps() const {
    if (arrivals_.size() < 2) return 0;
    double s =
        std::chrono::duration<double>(arrivals_.back().first - arrivals_.front().first).count();
    return s > 0 ? double(arrivals_.back().second - arrivals_.front().second) / s : 0;
}

void App::draw() {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    auto now = Clock::now();
    while (!messages_.empty() && messages_.front().until < now) messages_.pop_front();
    GlDisplay::DrawParams p;
    p.fbWidth = w;
    p.fbHeight = h;
    p.split = haveFrame_ && frame_.pipelines.size() > 1;
    p.divider = divider_;
    p.showDivider = showStats_;
    // The overlay's size follows the framebuffer's (a high-DPI one gets larger texels), so that
    // it is never cut off and leaves most of the image in view; the labels share its scale.
    const OverlayLayout layout = overlayLayout(w, h, showHelp_);
    const int scale = layout.scale;
    if (showStats_ || showHelp_) {
        OverlayInfo info;
        info.frame = haveFrame_ ? &frame_ : nullptr;
        info.split = req_.split;
        info.pipeline = req_.pipeline;
        info.pair = req_.pair;
        info.bounces = req_.bounces;
        info.accel = req_.accel;
        info.animate = config_.animate;
        info.fps = fps();
        info.framePath = config_.framePath;
        for (const Message& m : messages_) info.messages.push_back(m.text);
        info.stats = showStats_;
        info.help = showHelp_;
        TextCanvas canvas = makeOverlay(info, layout);
        display_.uploadOverlay(0, canvas.rgba(), canvas.width(), canvas.height());
        p.overlays.push_back({0, 0, 0, scale});
    }
    if (p.split && showStats_) {
        // Name each side next to the divider, at the bottom.
        int divider = int(std::lround(divider_ * float(w))), gap = 4 * scale;
        int y = h - labelSize_[1] * scale - gap;
        p.overlays.push_back({1, std::max(0, divider - labelSize_[0] * scale - gap), y, scale});
        p.overlays.push_back({2, divider + gap, y, scale});
    }
    display_.draw(p);
}

void App::saveScreenshot(const std::string& path) {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    draw();
    writeImage(decodeSrgb8(display_.readPixels(w, h), w, h), path);
}

int App::run() {
    const auto start = Clock::now();
    while (!glfwWindowShouldClose(window_)) {
        auto before = Clock::now();
        bool moving = false;
        for (int key : {GLFW_KEY_W, GLFW_KEY_A, GLFW_KEY_S, GLFW_KEY_D, GLFW_KEY_Q, GLFW_KEY_E})
            moving |= glfwGetKey(window_, key) == GLFW_PRESS;
        glfwWaitEventsTimeout(moving || drag_ != Drag::None ? 1.0 / 60 : 0.25);
        if (moving) moveCamera(std::chrono::duration<double>(Clock::now() - before).count());
        receive();
        if (!fatal_.empty()) throw Error(fatal_);
        auto due = [&](const ScriptedKey& k) {
            if (k.piece == 0) return framesShown() >= k.frame;
            return framesShown() >= k.frame ||
                   (haveFrame_ && (long long)frame_.index == k.frame && frame_.pieces >= k.piece);
        };
        while (!config_.keys.empty() && due(config_.keys.front())) {
            onKey(config_.keys.front().key);
            config_.keys.erase(config_.keys.begin());
        }
        if (config_.frames > 0 && framesShown() >= config_.frames) {
            auto now = Clock::now();
            double total = std::chrono::duration<double>(now - start).count();
            double first = std::chrono::duration<double>(firstArrival_.first - start).count();
            double rest = std::chrono::duration<double>(now - firstArrival_.first).count();
            if (!config_.screenshot.empty()) {
                saveScreenshot(config_.screenshot);
                std::printf("rtlab-view: wrote %s\n", config_.screenshot.c_str());
            }
            std::printf("rtlab-view: %lld frames in %.2f s: the first after %.2f s", config_.frames,
                        total, first);
            if (frame_.index > firstArrival_.second && rest > 0)
                std::printf(", then %.2f FPS", double(frame_.index - firstArrival_.second) / rest);
            for (const PipelineFrame& p : frame_.pipelines)
                std::printf(", %s %.1f ms device", p.name.c_str(), p.stats.deviceMs);
            // How the last frame came: in how many pieces, and how many were abandoned part way.
            std::printf(", accel %s, the last in %d piece%s, %llu restarted",
                        accelName(frame_.options.accel), frame_.pieces,
                        frame_.pieces == 1 ? "" : "s", (unsigned long long)frame_.restarts);
            std::printf("\n");
            glfwSwapBuffers(window_);
            return 0;
        }
        draw();
        glfwSwapBuffers(window_);
    }
    uint64_t done = renderer_.framesRendered();
    if (config_.frames > 0)
        throw Error("window closed after " + std::to_string(done) + " of " +
                    std::to_string(config_.frames) + " frames");
    std::printf("rtlab-view: window closed after %llu frames\n", (unsigned long long)done);
    return 0;
}

}  // namespace rt::view
