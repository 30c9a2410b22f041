// rtlab — the queue wavefront's frame machinery (queue.cpp): one frame's launches and their
// timing and splitting (QueueFrame), the bounces of one AA sample over the pool (QueuePass), and
// the helpers they share. Included by queue.cpp only; its own header so that each file stays
// readable.
#pragma once

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <tuple>

#include "core/error.h"
#include "wavefront/queue/queue.h"
#include "wavefront/queue/queue_layout.h"
#include "wavefront/queue/queue_split.h"

namespace rt::queue_frame {

// The local memory the extend kernels declare themselves; --queue-local-pad comes on top.
constexpr size_t kExtendLocalBytes = sizeof(int) * RT_Q_EXTEND_LOCAL_INTS;

// "Queue_ShadeGlass" -> "shade glass": the stage names --stats prints.
inline std::string stageName(const std::string& kernel) {
    std::string out;
    for (char ch : kernel.substr(kernel.find('_') + 1)) {
        if (std::isupper(static_cast<unsigned char>(ch)) && !out.empty()) out += ' ';
        out += char(std::tolower(static_cast<unsigned char>(ch)));
    }
    return out;
}

// The scene's feature defines and the queue's own: one program for every bounce limit, since B
// travels in the settings and the histogram is sized for the most bounces there can be
// (RT_Q_MAX_DEPTH), so changing B (the viewer's +/-, a sweep over B) builds nothing.
std::vector<std::string> programDefines(const Scene& scene, const RenderOptions& o, int group,
                                        bool packets, int dropLane) {
    std::vector<std::string> d = featureDefines(scene, o);
    d.push_back("RT_QUEUE_GROUP=" + std::to_string(group));
    if (const size_t pad = queueLocalPad(o); pad > 0)
        d.push_back("RT_Q_LOCAL_PAD=" + std::to_string(pad));
    // --queue-shade: the class mode's program is the one it always was.
    if (const QueueShadeMode shade = queueShade(o); shade == QueueShadeMode::Pattern)
        d.push_back("RT_QUEUE_SHADE=RT_Q_SHADE_PATTERN");
    else if (shade == QueueShadeMode::Sort)
        d.push_back("RT_QUEUE_SHADE=RT_Q_SHADE_SORT");
    if (packets) {
        d.push_back("RT_QUEUE_PACKETS");
        d.push_back("RT_PACKET=" + std::to_string(QueuePipeline::kPacket));
        if (dropLane >= 0) d.push_back("RT_PACKET_DROP_LANE=" + std::to_string(dropLane));
    }
    return d;
}

// One launch of a bounce's shade stage: a kernel over a queue whose length the kernel reads from
// counters[countWord] (-1: one work-group, the sort's scan of the per-material counts).
struct ShadeLaunch {
    const char* kernel;
    int countWord;
};

const char* const kShadeKernels[RT_Q_CLASSES] = {"Queue_ShadeMiss", "Queue_ShadeDiffuse",
                                                 "Queue_ShadeMirror", "Queue_ShadeGlass",
                                                 "Queue_ShadeProcedural"};
static_assert(std::tuple_size_v<decltype(QueueStats::shadeQueueRays)> == RT_Q_QUEUES);
static_assert(RT_Q_PATTERNS == RT_PATTERN_BUMP - RT_PATTERN_CHECKER + 1);

// --queue-shade pattern: the procedural class's kernel per pattern, RT_PATTERN_CHECKER first.
const char* const kPatternKernels[RT_Q_PATTERNS] = {"Queue_ShadeChecker", "Queue_ShadeMarble",
                                                    "Queue_ShadeWood", "Queue_ShadeGranite",
                                                    "Queue_ShadeBump"};

// The shade stage of a bounce in the order it is enqueued, as --queue-shade asks: one launch per
// queue that the scene's materials can fill (the others never launch), and for sort the counting
// sort of the hits before their one launch.
inline std::vector<ShadeLaunch> shadeLaunches(const Scene& scene, QueueShadeMode mode) {
    std::array<bool, RT_Q_CLASSES> classes{};
    std::array<bool, RT_Q_PATTERNS> patterns{};
    classes[RT_Q_MISS] = true;
    for (const dev::Material& m : scene.materials) {
        const int c = RT_Q_MATERIAL_CLASS(m);
        classes[c] = true;
        if (c == RT_Q_PROCEDURAL) patterns[m.pattern - RT_PATTERN_CHECKER] = true;
    }
    std::vector<ShadeLaunch> out = {{kShadeKernels[RT_Q_MISS], RT_Q_COUNT + RT_Q_MISS}};
    if (mode == QueueShadeMode::Sort) {
        if (scene.materials.empty()) return out;
        const int hits = RT_Q_COUNT + RT_Q_HITS;
        return {out[0],
                {"Queue_SortCount", hits},
                {"Queue_SortBuckets", -1},
                {"Queue_SortScatter", hits},
                {"Queue_ShadeSorted", hits}};
    }
    for (int c = RT_Q_MISS + 1; c < RT_Q_CLASSES; ++c) {
        if (!classes[c]) continue;
        if (c == RT_Q_PROCEDURAL && mode == QueueShadeMode::Pattern) {
            for (int p = 0; p < RT_Q_PATTERNS; ++p)
                if (patterns[p])
                    out.push_back({kPatternKernels[p],
                                   RT_Q_COUNT + RT_Q_PATTERN_QUEUE(RT_PATTERN_CHECKER + p)});
        } else {
            out.push_back({kShadeKernels[c], RT_Q_COUNT + c});
        }
    }
    return out;
}

// Stages that belong to shading: the shade kernels and, for --queue-shade sort, the sort.
inline bool isShadeStage(const std::string& kernel) {
    return kernel.rfind("Queue_Shade", 0) == 0 || kernel.rfind("Queue_Sort", 0) == 0;
}

// One launch of a frame: the kernel, the part of its queue it covered (a global work offset),
// and its event. `items` is exact, or, with countWord >= 0, a bound whose real length the kernel
// reads from counters[countWord]; QueueFrame::learn puts the real one in from a read-back.
struct QueueLaunch {
    std::string kernel;
    cl::Event event;
    size_t offset = 0, items = 0;
    int countWord = -1;
};

// One frame's launches, named for --stats: kernels, their local sizes, the events to time, and
// (--max-launch-ms) each launch split into pieces that fit the cap (wavefront/queue/queue_split.h).
class QueueFrame {
  public:
    // targetMs: --max-launch-ms (0: one launch per stage); fakeItemMs > 0 (tests only) prices
    // every launch at its items times that instead of its profiling event.
    QueueFrame(ClContext& cl, cl::Program& program, const DeviceScene& scene, int group,
               QueueKernels& kernels, StageCosts& costs, double targetMs, double fakeItemMs,
               bool packets)
        : cl_(cl),
          program_(program),
          scene_(scene),
          group_(group),
          kernels_(kernels.kernels),
          locals_(kernels.locals),
          costs_(costs),
          targetMs_(targetMs),
          fakeItemMs_(fakeItemMs),
          packets_(packets) {}

    // The extend and shadow kernels of this frame: per ray, or per packet of rays.
    const char* extendKernel() const { return packets_ ? "Queue_ExtendPacket" : "Queue_Extend"; }
    const char* shadowKernel() const { return packets_ ? "Queue_ShadowPacket" : "Queue_Shadow"; }
    // Queue items one work-item of `name` handles.
    size_t lanes(const std::string& name) const {
        return name.size() > 6 && name.compare(name.size() - 6, 6, "Packet") == 0
                   ? size_t(QueuePipeline::kPacket)
                   : 1;
    }

    Kernel& kernel(const std::string& name) {
        auto it = kernels_.find(name);
        if (it != kernels_.end()) return it->second;
        Kernel k(program_, name);
        size_t most = k.maxGroup(cl_.device().device);
        size_t local = size_t(group_);
        // Their local arrays need the full group.
        bool scan = name.rfind("Queue_Scan", 0) == 0 || name == "Queue_SortBuckets";
        if (scan && most < local)
            throw Error("queue pipeline: " + name + " runs at most " + std::to_string(most) +
                        " work-items per group on " + cl_.device().name + ", needs " +
                        std::to_string(local));
        while (local > most) local /= 2;
        locals_[name] = local;
        return kernels_.emplace(name, k).first->second;
    }
    // Scene arguments of a kernel that takes them, with this frame's settings.
    Kernel& sceneKernel(const std::string& name, const dev::RenderSettings& s) {
        Kernel& k = kernel(name);
        scene_.setArgs(k, s);
        return k;
    }
    // The arguments QUEUE_RAYS_PARAMS(prefix) declares (queue.cl): the per-ray state's fields
    // by the names core/ray_state.h gives them (prefixOrigin, ...), and prefixPixel.
    static Kernel& setRays(Kernel& k, const std::string& prefix, const QueueBuffers::Rays& r) {
#define QUEUE_RAYS_ARG(X, field, Field, ...) k.set(prefix + #Field, r.field);
        RT_RAY_STATE(QUEUE_RAYS_ARG, QUEUE_RAYS_ARG, _)
#undef QUEUE_RAYS_ARG
        return k.set(prefix + "Pixel", r.pixel);
    }
    // 1D launches over work-items [0, items) (none when zero): one, or pieces in whole
    // work-groups when the stage's measured cost per item says one would run past the cap. A
    // stage never measured starts with a probe that is timed before the rest is sized. With a
    // bound (countWord >= 0) the caller has made sure that one launch fits (wouldSplit).
    // A packet kernel's pieces are whole groups of packets, so each starts at a multiple of
    // its lanes and no packet straddles two pieces.
    void launch(const std::string& name, size_t items, int countWord = -1) {
        const size_t step = locals_.at(name) * lanes(name);
        for (size_t done = 0; done < items;) {
            size_t piece = costs_.piece(name, items - done, targetMs_, step);
            enqueue(name, done, piece, countWord);
            done += piece;
            if (done < items && !costs_.known(name)) {
                QueueLaunch& probe = launches_.back();
                probe.event.wait();
                costs_.learn(name, piece, ms(probe), targetMs_);
            }
        }
    }
    // Whether a launch of `name` over `items` would be split (it is over the cap).
    bool wouldSplit(const std::string& name, size_t items) const {
        return costs_.piece(name, items, targetMs_, locals_.at(name) * lanes(name)) < items;
    }
    // What the launches since the last call cost per item, stage by stage, for the pieces to
    // come; their events must be complete (the caller just waited on a read-back). `counters`
    // (the words just read, or null) gives the real length of launches made over a bound.
    void learn(const cl_int* counters) {
        struct Sum {
            size_t items = 0;
            double ms = 0;
        };
        std::map<std::string, Sum> sums;
        for (size_t i = learned_; i < launches_.size(); ++i) {
            QueueLaunch& l = launches_[i];
            if (l.countWord >= 0) {
                if (!counters) continue;
                l.items = std::min(l.items, size_t(std::max(counters[l.countWord], 0)));
                l.countWord = -1;
            }
            Sum& s = sums[l.kernel];
            s.items += l.items;
            s.ms += ms(l);
        }
        for (const auto& [kernel, s] : sums) costs_.learn(kernel, s.items, s.ms, targetMs_);
        learned_ = launches_.size();
    }
    // The longest stage among launches [first, end): its pieces' times summed, which is what
    // the whole queue took, as the admission limit needs it.
    double slowestStageMs(size_t first, size_t end) const {
        std::map<std::string, double> stages;
        for (size_t i = first; i < end; ++i) stages[launches_[i].kernel] += ms(launches_[i]);
        double most = 0;
        for (const auto& [kernel, t] : stages) most = std::max(most, t);
        return most;
    }
    double ms(const QueueLaunch& l) const {
        return fakeItemMs_ > 0 ? fakeItemMs_ * double(l.items) : eventMs(l.event);
    }
    std::vector<QueueLaunch>& launches() { return launches_; }
    const DeviceScene& scene() const { return scene_; }
    int group() const { return group_; }  // RT_QUEUE_GROUP, the scans' work-group size

  private:
    // Items [offset, offset + items) of the queue: work-items from offset / lanes on.
    void enqueue(const std::string& name, size_t offset, size_t items, int countWord) {
        size_t local = locals_.at(name), per = lanes(name);
        size_t workItems = (items + per - 1) / per,
               global = (workItems + local - 1) / local * local;
        cl::Event e;
        cl_.queue().enqueueNDRangeKernel(kernels_.at(name).get(), cl::NDRange(offset / per),
                                         cl::NDRange(global), cl::NDRange(local), nullptr, &e);
        launches_.push_back({name, e, offset, items, countWord});
    }

    ClContext& cl_;
    cl::Program& program_;
    const DeviceScene& scene_;
    int group_;
    std::map<std::string, Kernel>& kernels_;
    std::map<std::string, size_t>& locals_;
    StageCosts& costs_;
    double targetMs_, fakeItemMs_;
    bool packets_;
    std::vector<QueueLaunch> launches_;
    size_t learned_ = 0;  // launches_ before it were learned from
};

// The bounces of one AA sample: which pixels are still to start, and the pool's live rays.
class QueuePass {
  public:
    // learned: the admission limit an earlier frame of the same workload ended with, else 0.
    QueuePass(ClContext& cl, QueueFrame& f, const QueueBuffers& b, const RenderOptions& o,
              QueueStats& stats, size_t learned)
        : cl_(cl),
          f_(f),
          b_(b),
          o_(o),
          stats_(stats),
          onDevice_(queueLaunch(o) == QueueLaunchMode::Device),
          // --max-launch-ms: start with a probe and learn what a ray costs (see adaptLimit).
          limit_(o.maxLaunchMs <= 0 ? b.pool
                 : learned          ? std::min(b.pool, learned)
                                    : std::min(b.pool, kProbeRays)) {}
    size_t limit() const { return limit_; }

    // shade: the shade stage's launches (shadeLaunches); materials: the scene's count, the keys
    // of --queue-shade sort. started: called after each bounce with the pixels of the row
    // window started so far.
    void run(const dev::RenderSettings& settings, const std::vector<ShadeLaunch>& shade,
             int materials, const std::function<void(size_t started)>& started) {
        lights_ = settings.lightCount;
        shade_ = shade;
        materials_ = materials;
        sorts_ = std::any_of(shade.begin(), shade.end(), [](const ShadeLaunch& l) {
            return l.kernel == std::string("Queue_SortCount");
        });
        bindKernels(settings);
        next_ = firstPixel();
        retry_.clear();
        if (onDevice_) return runOnDevice(started);
        size_t n = admit(0);
        while (n > 0) {
            n = bounce(n);
            started(next_ - firstPixel());
        }
    }
    // The pixels of RenderOptions' row window: [firstPixel, endPixel).
    size_t firstPixel() const { return size_t(o_.rowBegin) * size_t(o_.width); }
    size_t endPixel() const { return size_t(o_.lastRow()) * size_t(o_.width); }

  private:
    // Arguments that stay the same through the pass (the settings carry the sample index).
    void bindKernels(const dev::RenderSettings& s) {
        const cl_int liveWord = onDevice_ ? RT_Q_LIVE : -1;
        Kernel& gen = f_.sceneKernel("Queue_Generate", s);
        QueueFrame::setRays(gen, "rays", b_.rays)
            .set("retry", b_.retry)
            .set("rayTally", b_.rayTally);
        Kernel& ext = f_.sceneKernel(f_.extendKernel(), s);
        QueueFrame::setRays(ext, "rays", b_.rays)
            .set("nodes", b_.nodes)
            .set("shadeQueues", b_.shadeQueues)
            .set("pool", cl_int(b_.pool))
            .set("shadowQueue", b_.shadowQueue)
            .set("counters", b_.counters)
            .set("nWord", liveWord)
            .set("rayTally", b_.rayTally);
        f_.sceneKernel(f_.shadowKernel(), s)
            .set("nodes", b_.nodes)
            .set("shadowQueue", b_.shadowQueue)
            .set("counters", b_.counters)
            .set("rayPixel", b_.rays.pixel)
            .set("rayMeta", b_.rays.depthType)
            .set("rayTally", b_.rayTally);
        for (const ShadeLaunch& l : shade_) {
            if (std::string(l.kernel).rfind("Queue_Shade", 0) != 0) continue;  // the sort's
            Kernel& k = f_.sceneKernel(l.kernel, s);
            QueueFrame::setRays(k, "rays", b_.rays)
                .set("nodes", b_.nodes)
                .set("shadeQueues", b_.shadeQueues)
                .set("pool", cl_int(b_.pool))
                .set("counters", b_.counters);
            QueueFrame::setRays(k, "staging", b_.staging)
                .set("contrib", b_.contrib)
                .set("children", b_.children);
        }
        if (sorts_) bindSort();
        bindBookkeeping();
    }

    // --queue-shade sort's counting sort (queue_sort.cl): buffers only.
    void bindSort() {
        for (const char* name : {"Queue_SortCount", "Queue_SortScatter"})
            f_.kernel(name)
                .set("nodes", b_.nodes)
                .set("shadeQueues", b_.shadeQueues)
                .set("pool", cl_int(b_.pool))
                .set("counters", b_.counters)
                .set("keys", b_.sortKeys);
        f_.kernel("Queue_SortBuckets")
            .set("keys", b_.sortKeys)
            .set("materials", cl_int(materials_));
    }

    // The scan, cut, accumulate and compact kernels: buffers only, no scene.
    void bindBookkeeping() {
        const cl_int liveWord = onDevice_ ? RT_Q_LIVE : -1, cutWord = onDevice_ ? RT_Q_CUT : -1;
        f_.kernel("Queue_ScanBlocks")
            .set("children", b_.children)
            .set("offsets", b_.offsets)
            .set("blockSums", b_.blockSums)
            .set("counters", b_.counters)
            .set("nWord", liveWord);
        f_.kernel("Queue_ScanSums")
            .set("blockSums", b_.blockSums)
            .set("counters", b_.counters)
            .set("liveWord", liveWord)
            .set("pool", cl_int(b_.pool));
        f_.kernel("Queue_FindCut")
            .set("children", b_.children)
            .set("offsets", b_.offsets)
            .set("blockSums", b_.blockSums)
            .set("pixels", b_.rays.pixel)
            .set("pool", cl_int(b_.pool))
            .set("counters", b_.counters);
        f_.kernel("Queue_Accumulate")
            .set("pixels", b_.rays.pixel)
            .set("meta", b_.rays.depthType)
            .set("contrib", b_.contrib)
            .set("sums", b_.sums)
            .set("counters", b_.counters)
            .set("cutWord", cutWord)
            .set("children", b_.children)
            .set("rayCounts", f_.scene().rayCountBuffer())
            .set("rayTally", b_.rayTally);
        Kernel& comp = f_.kernel("Queue_Compact");
        QueueFrame::setRays(comp, "staging", b_.staging)
            .set("children", b_.children)
            .set("offsets", b_.offsets)
            .set("blockSums", b_.blockSums);
        QueueFrame::setRays(comp, "rays", b_.rays)
            .set("counters", b_.counters)
            .set("cutWord", cutWord);
    }

    // Camera rays into slots [first, ...): pixels cut earlier first, then new ones, as many as
    // the pool (or the launch-time limit) has room for. Returns the live rays after it.
    size_t admit(size_t first) {
        size_t total = endPixel();
        size_t room = limit_ > first ? limit_ - first : 0;
        size_t count = std::min(room, retry_.size() + (total - next_));
        size_t fromRetry = std::min(count, retry_.size());
        if (fromRetry) {
            std::vector<cl_int> ids(retry_.begin(), retry_.begin() + long(fromRetry));
            retry_.erase(retry_.begin(), retry_.begin() + long(fromRetry));
            cl_.queue().enqueueWriteBuffer(b_.retry, CL_TRUE, 0, ids.size() * 4, ids.data());
            ++stats_.readbacks;  // a blocking write: the host waits for the queue as well
        }
        if (count == 0) return first;
        f_.kernel("Queue_Generate")
            .set("first", cl_int(first))
            .set("count", cl_int(count))
            .set("retryCount", cl_int(fromRetry))
            .set("nextPixel", cl_int(next_));
        f_.launch("Queue_Generate", count);
        next_ += count - fromRetry;
        return first + count;
    }

    // The stages of one bounce up to the prefix sum, over n rays (readback mode: exactly the
    // live rays; device mode: a bound on them, the kernels read the real count).
    void enqueueStages(size_t n) {
        cl_.queue().enqueueFillBuffer(b_.counters, cl_int(0), 0, RT_Q_PER_ITERATION * 4);
        f_.kernel(f_.extendKernel()).set("n", cl_int(n));
        f_.launch(f_.extendKernel(), n);
        // Shadow and shade run over queues that extend fills: over the bound n, each kernel
        // reads its queue's length. When one launch that long could run past --max-launch-ms,
        // the host reads the lengths first and launches each queue in pieces over them.
        bool split = !onDevice_ && lights_ > 0 && f_.wouldSplit(f_.shadowKernel(), n);
        for (const ShadeLaunch& l : shade_)
            split = split || (!onDevice_ && l.countWord >= 0 && f_.wouldSplit(l.kernel, n));
        cl_int len[RT_Q_PER_ITERATION] = {};
        if (split) {
            cl_.queue().enqueueReadBuffer(b_.counters, CL_TRUE, 0, sizeof len, len);
            ++stats_.readbacks;
            f_.learn(len);
        }
        auto queueLaunch = [&](const char* kernel, int word) {
            if (split)
                f_.launch(kernel, size_t(len[word]));
            else
                f_.launch(kernel, n, onDevice_ ? -1 : word);
        };
        if (lights_ > 0) queueLaunch(f_.shadowKernel(), RT_Q_SHADOW);
        if (sorts_)  // the per-material counts start from zero every bounce
            cl_.queue().enqueueFillBuffer(b_.sortKeys, cl_int(0), 0, size_t(materials_) * 4);
        for (const ShadeLaunch& l : shade_) {
            if (l.countWord >= 0)
                queueLaunch(l.kernel, l.countWord);
            else
                f_.launch(l.kernel, 1);  // one work-group
        }
        size_t group = size_t(f_.group());
        size_t blocks = (n + group - 1) / group;
        f_.kernel("Queue_ScanBlocks").set("n", cl_int(n));
        f_.launch("Queue_ScanBlocks", n);
        f_.kernel("Queue_ScanSums").set("blocks", cl_int(blocks));
        f_.launch("Queue_ScanSums", 1);
        ++stats_.iterations;
    }

    // Sums of rays [0, cut) to their pixels, their children to the pool's front.
    void enqueueAccumulate(size_t cut) {
        f_.kernel("Queue_Accumulate").set("cut", cl_int(cut));
        f_.launch("Queue_Accumulate", cut);
        f_.kernel("Queue_Compact").set("cut", cl_int(cut));
        f_.launch("Queue_Compact", cut);
    }

    // --queue-launch device: the pixels in waves of at most a pool of camera rays; each wave's
    // B + 1 bounces are enqueued without waiting. A bounce's bound: the wave's camera rays, then
    // C times the last bound, never past the pool. Paths are never cut: a bounce whose children
    // outgrow the pool raises RT_Q_OVERFLOW and the frame is rendered again with read-backs.
    void runOnDevice(const std::function<void(size_t started)>& started) {
        const size_t C = size_t(b_.branching);
        while (next_ < endPixel()) {
            size_t bound = admit(0);
            cl_.queue().enqueueFillBuffer(b_.counters, cl_int(bound), RT_Q_LIVE * 4, 4);
            for (int depth = 0; depth <= o_.bounces; ++depth) {
                enqueueStages(bound);
                enqueueAccumulate(bound);
                bound = std::min(b_.pool, bound * C);
            }
            started(next_ - firstPixel());
        }
    }

    // One bounce of the n live rays; returns the live rays of the next one.
    size_t bounce(size_t n) {
        cl::CommandQueue& q = cl_.queue();
        size_t firstEvent = f_.launches().size();
        enqueueStages(n);
        cl_int c[RT_Q_PER_ITERATION];
        q.enqueueReadBuffer(b_.counters, CL_TRUE, 0, sizeof c, c);
        ++stats_.readbacks;
        for (int k = 0; k < RT_Q_QUEUES; ++k) stats_.shadeQueueRays[k] += c[RT_Q_COUNT + k];
        size_t doneEvents = f_.launches().size();  // complete now: their times can be read
        if (o_.maxLaunchMs > 0) f_.learn(c);
        size_t cut = n, kept = size_t(c[RT_Q_CHILDREN]);
        if (kept > b_.pool) {
            f_.kernel("Queue_FindCut").set("n", cl_int(n));
            f_.launch("Queue_FindCut", 1);
            q.enqueueReadBuffer(b_.counters, CL_TRUE, 0, sizeof c, c);
            ++stats_.readbacks;
            cut = size_t(c[RT_Q_CUT]);
            kept = size_t(c[RT_Q_KEPT]);
            if (cut == 0) throw Error("queue pipeline: one path outgrew the pool (internal error)");
            reissue(cut, n);
        }
        enqueueAccumulate(cut);
        if (o_.maxLaunchMs > 0) adaptLimit(n, firstEvent, doneEvents);
        return admit(kept);
    }

    // The paths of rays [cut, n) lost their children: their pixels start again later, in order.
    void reissue(size_t cut, size_t n) {
        std::vector<cl_int> pixels(n - cut);
        cl_.queue().enqueueReadBuffer(b_.rays.pixel, CL_TRUE, cut * 4, pixels.size() * 4,
                                      pixels.data());
        ++stats_.readbacks;
        for (size_t i = 0; i < pixels.size(); ++i)
            if (i == 0 || pixels[i] != pixels[i - 1]) {
                retry_.push_back(pixels[i]);
                ++stats_.restartedPaths;
            }
    }

    // --max-launch-ms: admit no more rays than the slowest stage of this bounce (extend or
    // shadow, as a rule) handles in that time, all its pieces together. Launches keep under
    // the cap by their pieces (QueueFrame::launch); this keeps a bounce from needing many.
    void adaptLimit(size_t n, size_t firstEvent, size_t endEvent) {
        double ms = f_.slowestStageMs(firstEvent, endEvent);
        if (ms <= 0) return;
        // 0.8: aim below the target, bounces differ in cost; grow at most twofold per bounce,
        // as core/launch_planner.h does with rows it has not seen.
        double fit = double(n) * 0.8 * o_.maxLaunchMs / ms;
        size_t grown = std::min(size_t(fit), 2 * std::max(n, limit_));
        limit_ = std::clamp(grown, std::min(b_.pool, kProbeRays / 4), b_.pool);
    }

    // The first bounce of a workload: small, since one ray can cost a lot (a big mesh without an
    // acceleration structure tests every triangle, so a few thousand rays make a long launch);
    // it grows twofold per bounce from there. The floor keeps a slow bounce from starving the pool.
    static constexpr size_t kProbeRays = 256;
    ClContext& cl_;
    QueueFrame& f_;
    const QueueBuffers& b_;
    const RenderOptions& o_;
    QueueStats& stats_;
    bool onDevice_;
    size_t limit_, next_ = 0;
    int lights_ = 0, materials_ = 0;
    bool sorts_ = false;  // --queue-shade sort: the hits are sorted by material first
    std::vector<ShadeLaunch> shade_;
    std::deque<cl_int> retry_;
};

// The device's busy and idle time over a frame's kernels: the span from the first start to the
// last end, and the part of it covered by no kernel (the union of their intervals, so kernels
// that a device runs side by side are not counted twice).
inline std::pair<double, double> spanAndIdleMs(const std::vector<QueueLaunch>& launches) {
    std::vector<std::pair<cl_ulong, cl_ulong>> runs;
    for (const QueueLaunch& l : launches)
        runs.emplace_back(l.event.getProfilingInfo<CL_PROFILING_COMMAND_START>(),
                          l.event.getProfilingInfo<CL_PROFILING_COMMAND_END>());
    if (runs.empty()) return {0.0, 0.0};
    std::sort(runs.begin(), runs.end());
    cl_ulong busy = 0, reach = runs.front().first, last = 0;
    for (auto [start, end] : runs) {
        start = std::max(start, reach);
        if (end > start) busy += end - start;
        reach = std::max(reach, end);
        last = std::max(last, end);
    }
    double span = double(last - runs.front().first) * 1e-6;
    return {span, span - double(busy) * 1e-6};
}

}  // namespace rt::queue_frame
