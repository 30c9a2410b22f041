#include "megakernel/megakernel.h"

#include <chrono>

#include "core/error.h"

namespace rt {

std::vector<std::string> MegakernelPipeline::defines(const Scene& scene, const RenderOptions& o) {
    std::vector<std::string> d = featureDefines(scene, o);
    d.push_back(o.layout == RenderOptions::Layout::Tree ? "RT_LAYOUT_TREE" : "RT_LAYOUT_WEIGHTED");
    return d;
}

Image MegakernelPipeline::render(const Scene& scene, const RenderOptions& o) {
    auto t0 = std::chrono::steady_clock::now();
    checkOptions(scene, o);
    stats_ = {};
    stats_.branching = scene.branching();
    stats_.treeNodes = treeNodeCount(stats_.branching, o.bounces);
    if (o.layout == RenderOptions::Layout::Tree) {
        checkPrivateTree(stats_.branching, o.bounces, "megakernel's tree layout", true);
        stats_.privateBytes = treePrivateBytes(stats_.branching, o.bounces);
    } else {
        // Pending entries: a ray (2 x float3), a weight (float3) and a depth, 64 bytes.
        stats_.privateBytes = size_t(o.bounces * (stats_.branching - 1) + 1) * 64;
    }

    cl::Program program = cl_.program("megakernel.cl", defines(scene, o));
    stats_.program = cl_.lastProgramSource();
    if (!scene_ || !scene_->matches(scene, o.accel))
        scene_ = std::make_unique<DeviceScene>(cl_, scene, o.accel);
    size_t bytes = size_t(o.width) * o.height * 3 * sizeof(float);
    if (bytes != imageBytes_) {
        if (imageBytes_) cl_.release(2 * imageBytes_);
        image_ = cl_.allocate(bytes, CL_MEM_READ_WRITE, "the image buffer");
        centers_ = cl_.allocate(bytes, CL_MEM_READ_WRITE, "the adaptive-AA centre buffer");
        imageBytes_ = bytes;
    }

    dev::RenderSettings settings = makeSettings(scene, o);
    Launch range = launch2d(cl_.device(), o.width, o.height);
    Image out(o.width, o.height);
    try {
        if (o.countRays) scene_->resetRayCounts(cl_.queue());
        if (o.adaptiveAa && o.aa > 1) {
            cl::Kernel centers(program, "Megakernel_RenderCenters");
            scene_->setArgs(centers, settings);
            centers.setArg(DeviceScene::kFirstKernelArg, centers_);
            cl::Event e1, e2;
            cl_.queue().enqueueNDRangeKernel(centers, cl::NullRange, range.global, range.local,
                                             nullptr, &e1);
            cl::Kernel edges(program, "Megakernel_RenderEdges");
            scene_->setArgs(edges, settings);
            edges.setArg(DeviceScene::kFirstKernelArg, centers_);
            edges.setArg(DeviceScene::kFirstKernelArg + 1, image_);
            std::vector<cl::Event> wait{e1};
            cl_.queue().enqueueNDRangeKernel(edges, cl::NullRange, range.global, range.local,
                                             &wait, &e2);
            e2.wait();
            stats_.addKernel("centers", eventMs(e1));
            stats_.addKernel("edges", eventMs(e2));
        } else {
            cl::Kernel kernel(program, "Megakernel_Render");
            scene_->setArgs(kernel, settings);
            kernel.setArg(DeviceScene::kFirstKernelArg, image_);
            cl::Event e;
            cl_.queue().enqueueNDRangeKernel(kernel, cl::NullRange, range.global, range.local,
                                             nullptr, &e);
            e.wait();
            stats_.addKernel("megakernel", eventMs(e));
        }
        cl_.queue().enqueueReadBuffer(image_, CL_TRUE, 0, bytes, out.rgb.data());
        if (o.countRays) {
            stats_.rays = scene_->readRayCounts(cl_.queue());
            stats_.raysCounted = true;
        }
    } catch (const cl::Error& e) {
        throwClError(e, "megakernel frame on " + cl_.device().name);
    }
    stats_.hostMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

}  // namespace rt
