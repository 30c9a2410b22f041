// rtlab-view — the render thread. It owns the scene and every registered device pipeline,
// renders whatever the window last asked for, and hands back 8-bit frames and their stats. The
// window thread stays free for input and drawing, so a slow device (PoCL) never stalls the UI.
//
// Frames are rendered in pieces of rows (RenderOptions' row window), each sized to take about
// kPieceMs from what the last piece cost: a fast frame is one piece, a slow one (a big mesh with
// --accel none on a CPU device) shows row by row, and a new request from the window abandons
// it between two pieces and starts over. Pipelines without row windows render a frame whole.
//
// Buffers: each Pipeline keeps its device buffers while the scene object (its SceneId) and the
// frame size stay the same, so a still frame only changes the camera (kernel settings) and queues
// kernels. The pipelines have no call yet to update objects in place, and know a scene only by
// its SceneId, which an object keeps while it is changed in place; so the renderer never changes
// a scene a pipeline may hold a device copy of. A reload or an animation step writes a different
// slot (another Scene object), which the pipelines then upload, while their image and ray-tree
// buffers stay.
#pragma once

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "apps/options.h"
#include "core/cl_runtime.h"
#include "core/pipeline.h"
#include "core/scene.h"

namespace rt::view {

// Moves one sphere along a closed polyline, once around every `period` seconds: the viewer's
// stand-in for a scene-file "animate" entry until the loader accepts one.
struct Animation {
    int sphere = 0;
    std::vector<dev::Float3> path;
    double period = 6;
    dev::Float3 at(double seconds) const;
};
// The first sphere orbits its own centre on a horizontal circle of `radius`. Throws rt::Error when
// the scene has no sphere.
Animation orbitFirstSphere(const Scene& scene, float radius, double period);

// What the window wants rendered next; the latest request wins.
struct ViewRequest {
    dev::Camera camera{};
    bool split = false;               // two pipelines, both full frame
    std::string pipeline;             // when not split: any registered device pipeline
    std::array<std::string, 2> pair;  // split: left, right (registered device pipelines)
    int bounces = 0;
    RenderOptions::Accel accel = RenderOptions::Accel::Bv;
    uint64_t reloads = 0;  // bumped by R
};

// Whether two requests ask for the same frame (a newer, different one restarts the frame).
bool sameRequest(const ViewRequest& a, const ViewRequest& b);

struct PipelineFrame {
    std::string name;  // the registered pipeline name
    FrameStats stats;
    std::vector<uint8_t> rgb;  // sRGB, 3 bytes per pixel, rows top first
};

struct FrameOut {
    uint64_t index = 0;     // 1 for the first frame; a partial frame has the index it will complete
    int rowsDone = 0;       // rows rendered so far, from the top; the rest show the previous frame
    int pieces = 0;         // pieces rendered so far
    uint64_t restarts = 0;  // frames abandoned part way so far (the view changed), all frames
    size_t triangles = 0;   // in the scene rendered (the window's brute-force guard)
    bool complete() const { return rowsDone >= height; }
    int width = 0, height = 0;
    std::vector<PipelineFrame> pipelines;  // split: left then right
    double wallMs = 0;                     // render thread time for the frame
    RenderOptions options;                 // as rendered
    size_t deviceBytes = 0;                // ClContext::allocatedBytes()
    uint64_t sceneGeneration = 0;          // bumped by every successful reload
    dev::Camera sceneCamera{};             // the camera in the scene file
    std::string sceneName;
};

struct Notice {
    std::string text;  // one line
    bool fatal = false;
    // Set when the request's bounce limit or accel was refused: the values rendered instead.
    bool reverted = false;
    int bounces = 0;
    RenderOptions::Accel accel = RenderOptions::Accel::Bv;
};

class Renderer {
  public:
    struct Config {
        std::filesystem::path scenePath;
        cli::SceneFlags flags;  // command-line overrides of the scene's defaults
        bool animate = false;
        float orbitRadius = 0.8f;
        double orbitPeriod = 6;
        bool countRays = true;     // for Mrays/s
        long long frameLimit = 0;  // stop after this many frames (0 = never)
        // Animation clock: seconds per frame when > 0 (reproducible automation), else wall time.
        double fixedStep = 0;
        int pieceRows = 0;  // rows per piece when > 0 (--piece-rows), else sized by kPieceMs
    };
    static constexpr double kPieceMs = 100;  // what a piece should take: ten updates a second
    // `scene` is the already loaded scenePath; `wake` is called (from the render thread) after
    // each frame or notice, e.g. glfwPostEmptyEvent.
    Renderer(ClContext& cl, Scene scene, Config config, std::function<void()> wake);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    void start(const ViewRequest& first);
    void request(const ViewRequest& r);
    bool takeFrame(FrameOut& out);  // true when a frame newer than the last one taken is ready
    std::vector<Notice> takeNotices();
    uint64_t framesRendered() const;

  private:
    void loop();
    void renderPiece(const ViewRequest& r);
    void beginFrame(const ViewRequest& r);
    void fail(const std::string& failure);
    void publish();
    bool reload();
    void restoreBackup();
    void post(Notice n);
    RenderOptions optionsFor(int bounces, RenderOptions::Accel accel) const;
    int freeSlot() const;
    void install(Scene scene);
    void animate();
    void dropUnusedSlots();

    ClContext& cl_;
    Config config_;
    std::function<void()> wake_;

    // Render-thread state. slotLoad_ says which load a slot's content comes from (0 = empty).
    // Two slots per pipeline (held_), the current and the backup, so one is always free; sized
    // once, so that a slot stays one object.
    std::vector<Scene> slots_;
    std::vector<uint64_t> slotLoad_;
    uint64_t loads_ = 0;
    int current_ = 0;
    // A pipeline and the slots whose SceneId its device scene may carry: the one it rendered
    // last, plus the one it failed on (a failure may or may not have replaced its copy).
    struct Held {
        std::string name;
        std::unique_ptr<Pipeline> pipeline;
        std::set<int> slots;
    };
    std::vector<Held> held_;  // every registered device pipeline, in registry order
    Held& held(const std::string& name);
    bool slotHeld(int slot) const;  // by a pipeline or the backup
    std::optional<Animation> animation_;
    RenderOptions base_;
    dev::Camera fileCamera_{};
    // What a reload replaced, kept until the new scene renders once.
    struct Backup {
        int slot;
        std::optional<Animation> animation;
        RenderOptions base;
        dev::Camera fileCamera;
    };
    std::optional<Backup> backup_;
    std::pair<int, RenderOptions::Accel> good_;
    std::set<std::pair<int, RenderOptions::Accel>> refused_;
    uint64_t reloadsDone_ = 0, generation_ = 0;
    std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
    bool anyFrame_ = false, failed_ = false, reloaded_ = false;

    // The frame in progress, rendered piece by piece; `active` is false between frames.
    struct Progressive {
        bool active = false;
        ViewRequest request;
        std::pair<int, RenderOptions::Accel> choice;
        RenderOptions options;
        std::vector<Held*> order;
        bool windows = true;  // every pipeline in order renders row windows
        FrameOut out;
        std::chrono::steady_clock::time_point started;
    } frame_;
    uint64_t restarts_ = 0;
    // The last complete frame's pixels, per side: a partial frame shows them below its rows.
    std::array<std::vector<uint8_t>, 2> lastRgb_;
    // Piece sizing, while the workload (pipelines, options, scene) stays the same: a frame's
    // first piece from the last complete frame's cost per row, the next ones from the last
    // piece's, growing at most twofold (rows differ in cost: sky against a mesh). A new workload
    // starts with a probe of a few rows.
    std::string pieceKey_;
    double msPerRow_ = 0, frameMsPerRow_ = 0, frameMs_ = 0;
    int lastPieceRows_ = 0;  // in the frame in progress
    int nextPieceRows(int remaining) const;

    // Shared with the window thread.
    mutable std::mutex mutex_;
    std::condition_variable cv_;
    ViewRequest request_;
    FrameOut latest_;
    // published_ counts every frame or piece handed over, taken_ what the window took; rendered_
    // counts complete frames. After a partial piece the thread waits until the window took it,
    // so that every piece is seen and a key pressed at a piece reaches the frame in progress.
    uint64_t published_ = 0, taken_ = 0, rendered_ = 0;
    std::vector<Notice> notices_;
    bool stop_ = false;
    std::thread thread_;
};

}  // namespace rt::view
