#include "wavefront/tree/wavefront.h"

#include <algorithm>
#include <cstdio>
#include <limits>

#include "core/error.h"
#include "core/pipeline_registry.h"

namespace rt {

size_t WavefrontPipeline::pixelBytes(int branching, int bounces, size_t nodeBytes) {
    const size_t nodes = size_t(treeNodeCount(branching, bounces));
    return nodes * nodeBytes + size_t(RT_TRACED_WORDS(nodes)) * sizeof(cl_uint);
}

int WavefrontPipeline::tileRows(int width, int height, int branching, int bounces, size_t budget,
                                const std::string& budgetName, size_t nodeBytes) {
    auto rowBytes = [&](int b) { return size_t(width) * pixelBytes(branching, b, nodeBytes); };
    size_t row = rowBytes(bounces);
    if (row > budget) {
        const size_t nodes = size_t(treeNodeCount(branching, bounces));
        int fits = bounces;
        while (fits >= 0 && rowBytes(fits) > budget) --fits;
        // Named by what limits it (the budget), not by --bounces, which the user may not have set.
        std::string msg = "one row of the wavefront ray tree at bounce limit " +
                          std::to_string(bounces) + " (" + std::to_string(width) + " pixels x (" +
                          std::to_string(nodes) + " nodes x " + std::to_string(nodeBytes) +
                          " B + " + std::to_string(RT_TRACED_WORDS(nodes) * sizeof(cl_uint)) +
                          " B of traced flags) = " + std::to_string(row) + " B) exceeds " +
                          budgetName + " (" + std::to_string(budget) + " B); ";
        msg += fits >= 0 ? "the highest bounce limit that fits is " + std::to_string(fits)
                         : "not even bounce limit 0 fits";
        throw Error(msg, FailureKind::TreeRow);
    }
    return int(std::min<size_t>(size_t(height), budget / row));
}

Image WavefrontPipeline::renderFrame(const Scene& scene, const RenderOptions& o) {
    // The report's wavefront renders every AA sample of every pixel in fixed passes over the tree;
    // it has no centre-then-edges pass, so adaptive anti-aliasing is refused rather than ignored.
    if (o.adaptiveAa)
        throw Error(
            "--adaptive: the wavefront pipeline has no adaptive anti-aliasing (the "
            "megakernel and cpu pipelines do); drop the flag or use --pipeline mega");
    const int C = scene.branching();
    const long long treeNodes = treeNodeCount(C, o.bounces);
    const size_t flagWords = RT_TRACED_WORDS(size_t(treeNodes));
    // The image kernel walks the traced slots with one frame per depth (two colours and four
    // ints: WaveFrame in wavefront.cl), not a private copy of the tree.
    stats_.privateBytes = size_t(o.bounces + 1) * (2 * sizeof(cl_float3) + 4 * sizeof(cl_int));

    const DeviceInfo& dev = cl_.device();
    size_t budget = dev.maxAlloc;
    std::string budgetName = dev.name + "'s max allocation";
    if (o.memoryBudget && o.memoryBudget < budget) {
        budget = o.memoryBudget;
        budgetName = "--memory-budget";
    }
    // A row window (the viewer's pieces of a slow frame) renders rows [first, end) only, in tiles
    // of at most `rows` rows: the budget's, or the window's when it is smaller.
    const int first = o.rowBegin, end = o.lastRow();
    const size_t nodeBytes = dev::nodeBytes(scene.lights.size());
    const int frameRows = tileRows(o.width, o.height, C, o.bounces, budget, budgetName, nodeBytes);
    const int rows = std::min(frameRows, end - first);
    // What an out-of-memory error from the driver is told about the frame (NVIDIA's, for one, can
    // fail at launch when the global tree and the kernels' private memory together do not fit).
    const int memoryTiles = tileCount(end - first, rows);
    auto memoryHint = [&] {
        const double gib = double(size_t(o.width) * rows * pixelBytes(C, o.bounces, nodeBytes)) /
                           double(1ull << 30);
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      "the frame needs a %.2f GiB ray tree (%d row tile%s); lower --bounces or "
                      "--size, or set --memory-budget",
                      gib, memoryTiles, memoryTiles == 1 ? "" : "s");
        return std::string(buf);
    };

    cl::Program program = this->program("wavefront.cl", featureDefines(scene, o));
    DeviceScene& deviceScene = this->deviceScene(scene, o.accel);

    // The tree holds treeRows_ rows. A whole frame sizes it to its tile exactly; a window keeps a
    // larger tree of the same frame rather than reallocating for every piece, but never one
    // larger than the whole frame's tile (the budget).
    const size_t pixelSize = pixelBytes(C, o.bounces, nodeBytes);
    const bool keep = treeWidth_ == o.width && treePixelBytes_ == pixelSize && treeRows_ >= rows &&
                      treeRows_ <= frameRows;  // a whole frame: == rows
    const int capacityRows = keep ? treeRows_ : rows;
    const size_t pixels = size_t(o.width) * capacityRows;
    const size_t treeBytes = pixels * size_t(treeNodes) * nodeBytes;
    const size_t flagBytes = pixels * flagWords * sizeof(cl_uint);
    size_t imageBytes = size_t(o.width) * o.height * 3 * sizeof(float);
    try {
        if (treeBytes != tree_.bytes() || flagBytes != traced_.bytes()) {
            // Both go before either is made again: after a failed allocation neither names a
            // size it does not have, and the next frame allocates afresh.
            tree_.reset();
            traced_.reset();
            treeRows_ = treeWidth_ = 0;
            treePixelBytes_ = 0;
            tree_.ensure(cl_, treeBytes, "the wavefront ray tree");
            traced_.ensure(cl_, flagBytes, "the wavefront ray tree's flags");
            treeRows_ = capacityRows;
            treeWidth_ = o.width;
            treePixelBytes_ = pixelSize;
            needsClear_ = true;
        }
        image_.ensure(cl_, imageBytes, "the image buffer");
    } catch (const cl::Error& e) {
        throwClError(e, "preparing wavefront buffers", memoryHint());
    }
    stats_.addBuffer("ray tree", treeBytes);
    stats_.addBuffer("tree flags", flagBytes);
    stats_.addBuffer("image", imageBytes);
    // The tree held, both buffers: one tile's (a window's may be an earlier piece's, larger).
    stats_.extras["tree_bytes"] = treeBytes + flagBytes;
    stats_.extras["tree_pixel_bytes"] = pixelSize;
    stats_.extras["node_bytes"] = nodeBytes;  // a slot's payload (the memory floor)
    stats_.extras["memory_tiles"] = memoryTiles;

    Kernel trace(program, "Wavefront_Trace"), image(program, "Wavefront_Image"),
        reset(program, "Wavefront_Reset");
    reset.set("traced", traced_.get());
    // Reset clears `words` flag words, four per work-item.
    auto resetRange = [](size_t words) { return cl::NDRange((words + 3) / 4); };
    if (needsClear_) {
        // Every slot starts untraced; from then on the reset kernel keeps it so. The reset kernel
        // (64-bit indices) clears a new buffer rather than clEnqueueFillBuffer, which left stale
        // "traced" flags in trees over 2 GiB on NVIDIA's OpenCL (illegal-address failures).
        try {
            reset.set("words", cl_ulong(pixels * flagWords));
            cl_.queue().enqueueNDRangeKernel(reset.get(), cl::NullRange,
                                             resetRange(pixels * flagWords));
        } catch (const cl::Error& e) {
            throwClError(e, "clearing the wavefront ray tree", memoryHint());
        }
        needsClear_ = false;
    }
    dev::RenderSettings settings = makeSettings(scene, o);
    int samples = o.aa * o.aa;
    std::vector<cl::Event> events;  // trace, image, reset per pass, for the profile
    Image out(o.width, o.height);
    try {
        startRayCount(o);
        cl::Event last;
        bool haveLast = false;
        // A row costlier than --max-launch-ms alone is launched in pieces of columns, in steps
        // of the work-group width (one work-group row high), as the megakernel does.
        planner_.begin(o.maxLaunchMs,
                       launchKey(o, featureDefines(scene, o), {}, " aa" + std::to_string(o.aa)),
                       o.width, columnStep(dev));
        stats_.tiles = 0;
        // Progress in rows x AA passes, reported after each pass of each tile (a piece of a row
        // counts once the row is done).
        const long long total = (long long)(end - first) * samples;
        for (int row0 = first, tile = 0; row0 < end; row0 += tile) {
            // Rows bounded by the tree buffer and, when asked, by the time one launch may take.
            LaunchTile plan = planner_.next(end - row0);
            if (!plan.partialRow()) plan.rows = std::clamp(plan.rows, 1, rows);
            tile = plan.partialRow() ? 1 : plan.rows;
            ++stats_.tiles;
            size_t firstEvent = events.size();
            const TileRange range = tileRange(dev, o.width, plan);
            const bool rowDone = !plan.partialRow() || plan.col0 + plan.cols >= o.width;
            settings.rowOffset = row0;
            // AA in passes: one tree per pixel, reused by every sample; image accumulates. The
            // tile's P = width x tile pixels set the stride of the slot-major buffers.
            for (int s = 0; s < samples; ++s) {
                settings.sampleIndex = s;
                deviceScene.setArgs(trace, settings);
                trace.set("tree", tree_.get())
                    .set("traced", traced_.get())
                    .set("rowEnd", cl_int(row0 + tile));
                deviceScene.setArgs(image, settings);
                image.set("tree", tree_.get())
                    .set("traced", traced_.get())
                    .set("image", image_.get())
                    .set("rowEnd", cl_int(row0 + tile));
                cl::Event et, ei, er;
                std::vector<cl::Event> waitTrace;
                if (haveLast) waitTrace.push_back(last);
                cl_.queue().enqueueNDRangeKernel(trace.get(), range.offset, range.global,
                                                 range.local,
                                                 waitTrace.empty() ? nullptr : &waitTrace, &et);
                std::vector<cl::Event> waitImage{et};
                cl_.queue().enqueueNDRangeKernel(image.get(), range.offset, range.global,
                                                 range.local, &waitImage, &ei);
                // Only this tile's flags were set (its pixels' words come first in the buffer),
                // so only they need clearing; payloads are never cleared. A piece of a row clears
                // the whole row's words: the others are clear already, and the row's words are
                // strided by slot, so its own are not one range.
                size_t tileWords = size_t(o.width) * size_t(tile) * flagWords;
                reset.set("words", cl_ulong(tileWords));
                std::vector<cl::Event> waitReset{ei};
                cl_.queue().enqueueNDRangeKernel(reset.get(), cl::NullRange, resetRange(tileWords),
                                                 cl::NullRange, &waitReset, &er);
                events.insert(events.end(), {et, ei, er});
                last = er;
                haveLast = true;
                // setArg copies the settings, so the next pass may change them right away.
                if (progress_) {
                    er.wait();
                    reportProgress((long long)(row0 - first) * samples +
                                       (rowDone ? (long long)(tile) * (s + 1) : 0),
                                   total);
                }
            }
            stats_.launches += 3 * samples;
            if (o.maxLaunchMs > 0) {  // learn the cost per row from the slowest launch
                last.wait();
                double slowest = 0;
                for (size_t i = firstEvent; i < events.size(); ++i)
                    slowest = std::max(slowest, eventMs(events[i]));
                planner_.record(plan, slowest);
            }
            if (!rowDone) tile = 0;  // the row goes on in its next piece
        }
        // Only the window's rows: the others of the image buffer may hold an earlier frame's.
        const size_t rowBytes = size_t(o.width) * 3 * sizeof(float);
        cl_.queue().enqueueReadBuffer(image_.get(), CL_TRUE, size_t(first) * rowBytes,
                                      size_t(end - first) * rowBytes,
                                      out.rgb.data() + size_t(first) * o.width * 3);
        finishRayCount(o);
        if (o.countRays) {
            // Every traced primary, reflected or refracted ray fills one tree slot; shadow rays
            // live inside their node. What share of the slots a frame touched.
            double slots = double(o.width) * (end - first) * samples * double(treeNodes);
            if (!o.adaptiveAa && slots > 0)
                stats_.extras["tree_used"] =
                    double(stats_.rays[RT_RAY_PRIMARY] + stats_.rays[RT_RAY_REFLECTION] +
                           stats_.rays[RT_RAY_REFRACTION]) /
                    slots;
        }
        static const char* names[3] = {"trace", "image", "reset"};
        for (size_t i = 0; i < events.size(); ++i)
            stats_.addKernel(names[i % 3], eventMs(events[i]));
    } catch (const cl::Error& e) {
        throwClError(e, "wavefront frame on " + dev.name, memoryHint());
    }
    return out;
}

void WavefrontPipeline::poisonPayloads() {
    if (!tree_.bytes()) return;
    const cl_float nan = std::numeric_limits<float>::quiet_NaN();
    cl_.queue().enqueueFillBuffer(tree_.get(), nan, 0, tree_.bytes());
    cl_.queue().finish();
}

std::vector<uint32_t> WavefrontPipeline::tracedFlags() {
    std::vector<uint32_t> words(traced_.bytes() / sizeof(uint32_t));
    if (!words.empty())
        cl_.queue().enqueueReadBuffer(traced_.get(), CL_TRUE, 0, traced_.bytes(), words.data());
    return words;
}

}  // namespace rt

namespace rt {

void registerWavefrontTree(PipelineRegistry& registry) {
    PipelineInfo p;
    p.name = "wave";
    p.title = "wavefront (report's tree)";
    p.family = "wavefront";
    p.description = "trace, image and reset kernels around a global ray tree of W x rows x N slots";
    p.supports = {.adaptiveAa = false, .tiling = true, .rowWindow = true};
    p.fitsOnePiece = [](const Scene& scene, const RenderOptions& o, const DeviceInfo& dev) {
        size_t budget = dev.maxAlloc;
        if (o.memoryBudget && o.memoryBudget < budget) budget = o.memoryBudget;
        try {
            return WavefrontPipeline::tileRows(o.width, o.height, scene.branching(), o.bounces,
                                               budget, "",
                                               dev::nodeBytes(scene.lights.size())) >= o.height;
        } catch (const Error&) {
            return false;  // not even one row fits
        }
    };
    p.make = [](ClContext* cl) { return std::make_unique<WavefrontPipeline>(*cl); };
    registry.add(std::move(p));
}

}  // namespace rt
