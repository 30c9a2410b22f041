// rtlab-view — the render thread: reloads, animation, option changes that may be refused (a bounce
// limit past the private-memory limit, an accel that is not implemented), and frames handed back.
#include "apps/viewer_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "apps/viewer_srgb.h"
#include "core/accel.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "image/image_io.h"
#include "pipelines/registry.h"

namespace rt::view {

dev::Float3 Animation::at(double seconds) const {
    if (path.empty()) return {};
    double u = std::fmod(seconds / period, 1.0);
    if (u < 0) u += 1;
    u *= double(path.size());
    size_t i = size_t(u) % path.size(), j = (i + 1) % path.size();
    float f = float(u - std::floor(u));
    const dev::Float3 &a = path[i], &b = path[j];
    return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f};
}

bool sameRequest(const ViewRequest& a, const ViewRequest& b) {
    const dev::Camera &x = a.camera, &y = b.camera;
    return x.position.x == y.position.x && x.position.y == y.position.y &&
           x.position.z == y.position.z && x.yaw == y.yaw && x.pitch == y.pitch &&
           x.fovY == y.fovY && a.split == b.split && a.pipeline == b.pipeline && a.pair == b.pair &&
           a.bounces == b.bounces && a.accel == b.accel && a.reloads == b.reloads;
}

Animation orbitFirstSphere(const Scene& scene, float radius, double period) {
    if (scene.spheres.empty())
        throw Error("--animate: " + scene.source.string() + " has no sphere to move");
    Animation a;
    a.sphere = 0;
    a.period = period;
    dev::Float3 c = scene.spheres[0].center;
    const int steps = 48;
    for (int i = 0; i < steps; ++i) {
        double t = 2 * M_PI * i / steps;
        a.path.push_back(
            {c.x + radius * float(std::cos(t)), c.y, c.z + radius * float(std::sin(t))});
    }
    return a;
}

Renderer::Renderer(ClContext& cl, Scene scene, Config config, std::function<void()> wake)
    : cl_(cl), config_(std::move(config)), wake_(std::move(wake)) {
    base_ = config_.flags.apply(scene.defaults);
    base_.countRays = config_.countRays;
    if (config_.animate)
        animation_ = orbitFirstSphere(scene, config_.orbitRadius, config_.orbitPeriod);
    fileCamera_ = scene.camera;
    for (const std::string& name : pipelineRegistry().names(true))
        held_.push_back({name, makePipeline(name, &cl_), {}});
    slots_.resize(2 * held_.size() + 2);
    slotLoad_.assign(slots_.size(), 0);
    install(std::move(scene));
    good_ = {base_.bounces, base_.accel};
}

Renderer::Held& Renderer::held(const std::string& name) {
    for (Held& h : held_)
        if (h.name == name) return h;
    throw Error("--pipeline " + name + ": not a device pipeline");
}

bool Renderer::slotHeld(int s) const {
    for (const Held& h : held_)
        if (h.slots.count(s)) return true;
    return backup_ && backup_->slot == s;
}

Renderer::~Renderer() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
}

int Renderer::freeSlot() const {
    // At most 2 per pipeline held, the current and the backup slot are taken: one is free.
    for (int s = 0; s < int(slots_.size()); ++s)
        if (s != current_ && !slotHeld(s)) return s;
    throw Error("internal: no free scene slot");
}

void Renderer::install(Scene scene) {
    int s = freeSlot();
    slots_[size_t(s)] = std::move(scene);
    slotLoad_[size_t(s)] = ++loads_;
    current_ = s;
}

void Renderer::animate() {
    double t =
        config_.fixedStep > 0
            ? double(rendered_) * config_.fixedStep
            : std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    int s = freeSlot();  // another Scene object (SceneId), so the pipelines upload the moved one
    if (slotLoad_[size_t(s)] != slotLoad_[size_t(current_)]) {
        slots_[size_t(s)] = slots_[size_t(current_)];
        slotLoad_[size_t(s)] = slotLoad_[size_t(current_)];
    }
    slots_[size_t(s)].spheres[size_t(animation_->sphere)].center = animation_->at(t);
    current_ = s;
}

void Renderer::dropUnusedSlots() {
    for (int s = 0; s < int(slots_.size()); ++s)
        if (slotLoad_[size_t(s)] && slotLoad_[size_t(s)] != slotLoad_[size_t(current_)] &&
            !slotHeld(s)) {
            slots_[size_t(s)] = Scene();
            slotLoad_[size_t(s)] = 0;
        }
}

void Renderer::start(const ViewRequest& first) {
    request_ = first;
    thread_ = std::thread([this] { loop(); });
}

void Renderer::request(const ViewRequest& r) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        request_ = r;
    }
    cv_.notify_all();
}

bool Renderer::takeFrame(FrameOut& out) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (published_ <= taken_) return false;
        out = latest_;  // a copy: the render thread goes on filling the frame in progress
        taken_ = published_;
    }
    cv_.notify_all();  // a partial piece waits to be taken
    return true;
}

std::vector<Notice> Renderer::takeNotices() {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(notices_, {});
}

uint64_t Renderer::framesRendered() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return rendered_;
}

void Renderer::post(Notice n) {
    std::lock_guard<std::mutex> lock(mutex_);
    notices_.push_back(std::move(n));
}

void Renderer::loop() {
    for (;;) {
        ViewRequest r;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            cv_.wait(lock, [&] {
                if (stop_) return true;
                if (failed_ ||
                    (config_.frameLimit > 0 && (long long)rendered_ >= config_.frameLimit))
                    return false;
                // After a partial piece: on once the window took it, or asked for something new.
                return !frame_.active || taken_ >= published_ ||
                       !sameRequest(request_, frame_.request);
            });
            if (stop_) return;
            r = request_;
        }
        try {
            renderPiece(r);
        } catch (const std::exception& e) {  // nothing may escape the thread
            failed_ = true;
            post({std::string("render thread: ") + e.what(), true});
        }
        wake_();
    }
}

RenderOptions Renderer::optionsFor(int bounces, RenderOptions::Accel accel) const {
    RenderOptions o = base_;
    o.bounces = bounces;
    o.accel = accel;
    return o;
}

bool Renderer::reload() {
    Scene fresh;
    RenderOptions base;
    std::optional<Animation> animation;
    try {
        fresh = loadScene(config_.scenePath, readImage);
        base = config_.flags.apply(fresh.defaults);
        base.countRays = config_.countRays;
        if (config_.animate)
            animation = orbitFirstSphere(fresh, config_.orbitRadius, config_.orbitPeriod);
    } catch (const std::exception& e) {
        post({std::string("reload failed, kept the previous scene: ") + e.what()});
        return false;
    }
    backup_ = Backup{current_, animation_, base_, fileCamera_};
    fileCamera_ = fresh.camera;
    install(std::move(fresh));
    animation_ = animation;
    base_ = base;
    refused_.clear();
    return true;
}

void Renderer::restoreBackup() {
    current_ = backup_->slot;
    animation_ = backup_->animation;
    base_ = backup_->base;
    fileCamera_ = backup_->fileCamera;
    backup_.reset();
    refused_.clear();
}

int Renderer::nextPieceRows(int remaining) const {
    if (!frame_.windows) return remaining;
    if (config_.pieceRows > 0) return std::min(remaining, config_.pieceRows);
    const int height = frame_.options.height;
    if (lastPieceRows_ == 0) {  // the frame's first piece
        if (frameMsPerRow_ <= 0) return std::min(remaining, std::max(1, height / 32));  // probe
        return std::clamp(int(kPieceMs / frameMsPerRow_), 1, remaining);
    }
    int rows = int(std::min(double(2 * lastPieceRows_), kPieceMs / msPerRow_));
    return std::clamp(rows, 1, remaining);
}

void Renderer::beginFrame(const ViewRequest& r) {
    if (r.reloads != reloadsDone_) {
        reloadsDone_ = r.reloads;
        reloaded_ |= reload();
    }
    Progressive& p = frame_;
    p.request = r;
    p.choice = {r.bounces, r.accel};
    if (refused_.count(p.choice)) p.choice = good_;
    p.options = optionsFor(p.choice.first, p.choice.second);

    if (animation_) animate();
    Scene& scene = slots_[size_t(current_)];
    scene.camera = r.camera;  // travels in the kernel settings, not in the device scene

    p.order.clear();
    if (r.split)
        p.order = {&held(r.pair[0]), &held(r.pair[1])};
    else
        p.order = {&held(r.pipeline)};
    p.windows = true;
    std::string key = std::to_string(slotLoad_[size_t(current_)]);
    for (Held* h : p.order) {
        p.windows &= pipelineInfo(h->name).supports.rowWindow;
        key += " " + h->name;
    }
    const RenderOptions& o = p.options;
    key += " " + std::to_string(o.width) + "x" + std::to_string(o.height) + " B" +
           std::to_string(o.bounces) + " " + accelName(o.accel);
    if (key != pieceKey_) {
        pieceKey_ = key;
        msPerRow_ = frameMsPerRow_ = 0;
    }
    lastPieceRows_ = 0;
    frameMs_ = 0;

    FrameOut& f = p.out;
    f = FrameOut();
    f.width = o.width;
    f.height = o.height;
    f.options = o;
    f.sceneName = scene.name;
    f.triangles = scene.triangles.size();
    for (size_t i = 0; i < p.order.size(); ++i) {
        PipelineFrame pf{p.order[i]->name, {}, {}};
        // Below the rows done, the last complete frame (when it has this size), else black.
        if (lastRgb_[i].size() == size_t(o.width) * o.height * 3)
            pf.rgb = lastRgb_[i];
        else
            pf.rgb.assign(size_t(o.width) * o.height * 3, 0);
        f.pipelines.push_back(std::move(pf));
    }
    p.started = std::chrono::steady_clock::now();
    p.active = true;
}

// What one piece cost, added to the frame's: times, launches and rays sum over the pieces.
static void addPiece(FrameStats& frame, const FrameStats& piece, bool first) {
    if (first) {
        frame = piece;
        return;
    }
    for (const auto& [name, ms] : piece.kernelMs) frame.addKernel(name, ms);
    frame.longestLaunchMs = std::max(frame.longestLaunchMs, piece.longestLaunchMs);
    frame.hostMs += piece.hostMs;
    frame.tiles += piece.tiles;
    frame.launches += piece.launches;
    frame.raysCounted = frame.raysCounted && piece.raysCounted;
    for (int t = 0; t < RT_RAY_TYPES; ++t) frame.rays[size_t(t)] += piece.rays[size_t(t)];
    frame.buffers = piece.buffers;
    frame.extras = piece.extras;
}

void Renderer::renderPiece(const ViewRequest& r) {
    if (frame_.active && !sameRequest(r, frame_.request)) {
        frame_.active = false;  // the view changed: this frame will never be shown whole
        ++restarts_;
    }
    if (!frame_.active) beginFrame(r);
    Progressive& p = frame_;
    FrameOut& f = p.out;
    Scene& scene = slots_[size_t(current_)];
    RenderOptions o = p.options;
    const int rows = nextPieceRows(o.height - f.rowsDone);
    if (rows < o.height) {
        o.rowBegin = f.rowsDone;
        o.rowEnd = f.rowsDone + rows;
    }
    auto t0 = std::chrono::steady_clock::now();
    try {
        Image image;
        std::vector<uint8_t> rgb;
        for (size_t i = 0; i < p.order.size(); ++i) {
            Held* h = p.order[i];
            h->slots.insert(current_);
            image = h->pipeline->render(scene, o);
            h->slots = {current_};
            addPiece(f.pipelines[i].stats, h->pipeline->stats(), f.pieces == 0);
            encodeSrgb8(image, rgb);
            const size_t row = size_t(o.width) * 3;
            std::copy(rgb.begin() + long(size_t(f.rowsDone) * row),
                      rgb.begin() + long(size_t(f.rowsDone + rows) * row),
                      f.pipelines[i].rgb.begin() + long(size_t(f.rowsDone) * row));
        }
    } catch (const cl::Error& e) {
        return fail(std::string("OpenCL error in ") + e.what() + ": " + clErrorName(e.err()));
    } catch (const std::exception& e) {
        return fail(e.what());
    }
    auto now = std::chrono::steady_clock::now();
    const double pieceMs = std::chrono::duration<double, std::milli>(now - t0).count();
    msPerRow_ = std::max(pieceMs / rows, 1e-6);
    lastPieceRows_ = rows;
    frameMs_ += pieceMs;
    f.rowsDone += rows;
    ++f.pieces;
    f.wallMs = std::chrono::duration<double, std::milli>(now - p.started).count();
    if (f.complete()) {
        frameMsPerRow_ = std::max(frameMs_ / f.height, 1e-6);
        if (reloaded_) ++generation_;
        reloaded_ = false;
        backup_.reset();
        dropUnusedSlots();
        good_ = p.choice;
        anyFrame_ = true;
        p.active = false;
        for (size_t i = 0; i < f.pipelines.size(); ++i) lastRgb_[i] = f.pipelines[i].rgb;
    }
    publish();
}

void Renderer::publish() {
    FrameOut& f = frame_.out;
    f.deviceBytes = cl_.allocatedBytes();
    f.sceneGeneration = generation_;
    f.sceneCamera = fileCamera_;
    f.restarts = restarts_;
    std::lock_guard<std::mutex> lock(mutex_);
    if (f.complete()) ++rendered_;
    f.index = rendered_ + (f.complete() ? 0 : 1);
    latest_ = f;
    ++published_;
}

void Renderer::fail(const std::string& failure) {
    frame_.active = false;
    for (Held& h : held_)
        if (h.slots.size() > 2) {  // keep freeSlot()'s count: start this one afresh
            h.pipeline = makePipeline(h.name, &cl_);
            h.slots.clear();
        }
    if (backup_) {
        restoreBackup();
        reloaded_ = false;
        post({"reload failed, kept the previous scene: " + failure});
    } else if (!anyFrame_ || frame_.choice == good_) {
        failed_ = true;
        post({failure, true});
    } else {
        refused_.insert(frame_.choice);
        post({failure, false, true, good_.first, good_.second});
    }
}

}  // namespace rt::view
