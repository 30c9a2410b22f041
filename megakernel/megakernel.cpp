#include "megakernel/megakernel.h"

#include <algorithm>

#include "core/error.h"
#include "core/pipeline_registry.h"
#include "megakernel/megakernel_options.h"

namespace rt {

// The weighted layout's stack: depth-first, one pending sibling per level, so B * (C - 1) + 1
// entries.
static int weightedStackEntries(int branching, int bounces) {
    return bounces * (branching - 1) + 1;
}

std::vector<std::string> MegakernelPipeline::defines(const Scene& scene, const RenderOptions& o) {
    std::vector<std::string> d = featureDefines(scene, o);
    // The private arrays are sized by B: the whole tree, or the stack of pending rays (a scene
    // without refraction needs one entry whatever B is, and shares its program across B).
    if (megaLayout(o) == MegaLayout::Tree) {
        d.push_back("RT_LAYOUT_TREE");
        d.push_back(treeNodesDefine(scene, o.bounces));
    } else {
        d.push_back("RT_LAYOUT_WEIGHTED");
        d.push_back("RT_STACK_SIZE=" +
                    std::to_string(weightedStackEntries(scene.branching(), o.bounces)));
    }
    return d;
}

std::vector<std::string> MegakernelPipeline::buildOptions(const RenderOptions& o) const {
    return registerCapBuildOptions(megaMaxRegisters(o), cl_.device());
}

size_t MegakernelPipeline::privateBytes(const Scene& scene, const RenderOptions& o) {
    if (megaLayout(o) == MegaLayout::Tree)
        return treePrivateBytes(scene.branching(), o.bounces, dev::nodeBytes(scene.lights.size()));
    // Pending entries: a ray (2 x float3), a weight (float3) and a depth, 64 bytes.
    return size_t(weightedStackEntries(scene.branching(), o.bounces)) * 64;
}

Image MegakernelPipeline::renderFrame(const Scene& scene, const RenderOptions& o) {
    const int branching = scene.branching();
    if (megaLayout(o) == MegaLayout::Tree)
        checkPrivateTree(branching, o.bounces, "megakernel's tree layout",
                         " (or use --layout weighted)", dev::nodeBytes(scene.lights.size()));
    stats_.privateBytes = privateBytes(scene, o);

    const cl::Program program =
        rayLoopProgram("megakernel.cl", defines(scene, o), buildOptions(o), o);
    DeviceScene& deviceScene = this->deviceScene(scene, o.accel);
    size_t bytes = size_t(o.width) * o.height * 3 * sizeof(float);
    const bool adaptive = o.adaptiveAa && o.aa > 1;
    // The image, and for adaptive anti-aliasing the centre samples; a new image size drops
    // both.
    if (image_.ensure(cl_, bytes, "the image buffer")) centers_.reset();
    if (adaptive) centers_.ensure(cl_, bytes, "the adaptive-AA centre buffer");
    stats_.addBuffer("image", bytes);
    if (adaptive) stats_.addBuffer("adaptive-AA centres", bytes);

    dev::RenderSettings settings = makeSettings(scene, o);
    Image out(o.width, o.height);
    const int first = o.rowBegin, last = o.lastRow();
    planner_.begin(
        o.maxLaunchMs,
        launchKey(o, defines(scene, o), buildOptions(o)) + (o.adaptiveAa ? " adaptive" : ""),
        o.width, columnStep(cl_.device()));
    // Progress in rows x passes; the adaptive centres cover one row more on each side.
    const int centreFirst = std::max(0, first - 1), centreLast = std::min(o.height, last + 1);
    const long long total = (last - first) + (adaptive ? centreLast - centreFirst : 0);
    long long done = 0;
    // One pass over rows [from, to) in tiles sized by the planner (whole rows, or columns of one
    // row when a row alone would run past --max-launch-ms).
    auto pass = [&](Kernel& kernel, const char* name, int from, int to) {
        for (int row0 = from; row0 < to;) {
            LaunchTile tile = planner_.next(to - row0);
            settings.rowOffset = row0;
            deviceScene.setArgs(kernel, settings);
            cl::Event e;
            TileRange range = tileRange(cl_.device(), o.width, tile);
            cl_.queue().enqueueNDRangeKernel(kernel.get(), range.offset, range.global, range.local,
                                             nullptr, &e);
            e.wait();
            double ms = eventMs(e);
            planner_.record(tile, ms);
            stats_.addKernel(name, ms);
            ++stats_.launches;
            if (tile.partialRow() && tile.col0 + tile.cols < o.width) continue;  // row goes on
            row0 += tile.rows;
            reportProgress(done += tile.rows, total);
        }
    };
    try {
        startRayCount(o);
        if (adaptive) {
            // Every centre first: an edge test reads the neighbouring rows' centres.
            Kernel centers(program, "Megakernel_RenderCenters");
            centers.set("centers", centers_.get());
            pass(centers, "centers", centreFirst, centreLast);
            Kernel edges(program, "Megakernel_RenderEdges");
            edges.set("centers", centers_.get()).set("image", image_.get());
            pass(edges, "edges", first, last);
        } else {
            Kernel kernel(program, "Megakernel_Render");
            kernel.set("image", image_.get());
            pass(kernel, "megakernel", first, last);
        }
        const size_t rowBytes = size_t(o.width) * 3 * sizeof(float);
        cl_.queue().enqueueReadBuffer(image_.get(), CL_TRUE, size_t(first) * rowBytes,
                                      size_t(last - first) * rowBytes,
                                      out.rgb.data() + size_t(first) * o.width * 3);
        finishRayCount(o);
    } catch (const cl::Error& e) {
        throwClError(e, "megakernel frame on " + cl_.device().name,
                     "the megakernel keeps " + std::to_string(stats_.privateBytes / 1024) +
                         " KiB of private ray storage per work-item; lower --bounces or --size, "
                         "or use --layout weighted");
    }
    return out;
}

}  // namespace rt

namespace rt {

void registerMegakernel(PipelineRegistry& registry) {
    PipelineInfo p;
    p.name = "mega";
    p.title = "megakernel";
    p.family = "megakernel";
    p.description = "one kernel launch per frame; each work-item keeps its rays in private memory";
    p.supports = {.adaptiveAa = true, .tiling = false, .rowWindow = true};
    p.options = megakernelOptions();
    p.variants = megakernelVariants();
    p.make = [](ClContext* cl) { return std::make_unique<MegakernelPipeline>(*cl); };
    registry.add(std::move(p));
}

}  // namespace rt
