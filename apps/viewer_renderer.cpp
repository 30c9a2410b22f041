// rtlab-view — the render thread: reloads, animation, option changes that may be refused (a bounce
// limit past the private-memory limit, an accel that is not implemented), and frames handed back.
#include "apps/viewer_renderer.h"

#include <chrono>
#include <cmath>

#include "apps/viewer_srgb.h"
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
        a.path.push_back({c.x + radius * float(std::cos(t)), c.y, c.z + radius * float(std::sin(t))});
    }
    return a;
}

Renderer::Renderer(ClContext& cl, Scene scene, Config config, std::function<void()> wake)
    : cl_(cl), config_(std::move(config)), wake_(std::move(wake)) {
    base_ = config_.flags.apply(scene.defaults);
    base_.countRays = config_.countRays;
    if (config_.animate) animation_ = orbitFirstSphere(scene, config_.orbitRadius, config_.orbitPeriod);
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
    double t = config_.fixedStep > 0
                   ? double(rendered_) * config_.fixedStep
                   : std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    int s = freeSlot();  // a new address, so the pipelines upload the moved object
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
    std::lock_guard<std::mutex> lock(mutex_);
    if (latest_.index <= taken_) return false;
    out = std::move(latest_);
    taken_ = out.index;
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
                return stop_ || (!failed_ && (config_.frameLimit == 0 ||
                                              (long long)rendered_ < config_.frameLimit));
            });
            if (stop_) return;
            r = request_;
        }
        try {
            renderOne(r);
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

void Renderer::renderOne(const ViewRequest& r) {
    bool reloaded = false;
    if (r.reloads != reloadsDone_) {
        reloadsDone_ = r.reloads;
        reloaded = reload();
    }
    std::pair<int, RenderOptions::Accel> choice{r.bounces, r.accel};
    if (refused_.count(choice)) choice = good_;
    RenderOptions o = optionsFor(choice.first, choice.second);

    if (animation_) animate();
    Scene& scene = slots_[size_t(current_)];
    scene.camera = r.camera;  // travels in the kernel settings, not in the device scene

    auto t0 = std::chrono::steady_clock::now();
    FrameOut f;
    std::string failure;
    try {
        std::vector<Held*> order;
        if (r.split) order = {&held(r.pair[0]), &held(r.pair[1])};
        else order = {&held(r.pipeline)};
        for (Held* h : order) {
            h->slots.insert(current_);
            Image image = h->pipeline->render(scene, o);
            h->slots = {current_};
            PipelineFrame pf{h->name, h->pipeline->stats(), {}};
            encodeSrgb8(image, pf.rgb);
            f.pipelines.push_back(std::move(pf));
        }
    } catch (const cl::Error& e) {
        failure = std::string("OpenCL error in ") + e.what() + ": " + clErrorName(e.err());
    } catch (const std::exception& e) {
        failure = e.what();
    }

    if (!failure.empty()) {
        for (Held& h : held_)
            if (h.slots.size() > 2) {  // keep freeSlot()'s count: start this one afresh
                h.pipeline = makePipeline(h.name, &cl_);
                h.slots.clear();
            }
        if (backup_) {
            restoreBackup();
            post({"reload failed, kept the previous scene: " + failure});
        } else if (!anyFrame_ || choice == good_) {
            failed_ = true;
            post({failure, true});
        } else {
            refused_.insert(choice);
            post({failure, false, true, good_.first, good_.second});
        }
        return;
    }
    if (reloaded) ++generation_;
    backup_.reset();
    dropUnusedSlots();
    good_ = choice;
    anyFrame_ = true;
    f.width = o.width;
    f.height = o.height;
    f.options = o;
    f.wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    f.deviceBytes = cl_.allocatedBytes();
    f.sceneGeneration = generation_;
    f.sceneCamera = fileCamera_;
    f.sceneName = scene.name;
    std::lock_guard<std::mutex> lock(mutex_);
    f.index = ++rendered_;
    latest_ = std::move(f);
}

}  // namespace rt::view
