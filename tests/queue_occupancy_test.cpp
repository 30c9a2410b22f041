// Queue wavefront, --queue-group and --queue-local-pad: how many work-items a group of its kernels
// holds, and local memory that holds nothing, so that fewer groups are resident at once (what a
// megakernel's registers cost it, asked of the queue). Neither changes a ray's arithmetic or the
// order its contributions are summed in, so the image keeps its bits and the rays their counts;
// the pad must reach the kernels it names, and sizes the device cannot take are refused by name.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "core/error.h"
#include "core/scene_loader.h"
#include "image/image_io.h"
#include "scratch_dir.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"
#include "wavefront/queue/queue.h"

namespace rt {
namespace {

// A wall of small spheres of 16 materials (scripts/make-map.py): patterns, mirrors and glass side
// by side, so that every stage kernel runs.
Scene occupancyWall() { return test::mapWall(4, "0.5", 2, "48x32"); }

RenderOptions occupancyOptions(const Scene& scene) {
    RenderOptions o = scene.defaults;
    o.width = 48;
    o.height = 32;
    o.bounces = 4;
    o.aa = 1;
    o.countRays = true;
    return o;
}

struct OccupancyFrame {
    Image image;
    FrameStats stats;
};

OccupancyFrame renderQueue(const Scene& scene, const RenderOptions& o) {
    QueuePipeline queue(test::device());
    Image image = queue.render(scene, o);
    return {image, queue.stats()};
}

double localBytes(const FrameStats& s, const std::string& kernel) {
    auto it = s.kernelResources.find(kernel + ".local_bytes");
    return it == s.kernelResources.end() ? -1.0 : it->second;
}

TEST(QueueOccupancy, GroupSizesKeepTheBits) {
    const Scene scene = occupancyWall();
    const RenderOptions o = occupancyOptions(scene);
    const OccupancyFrame base = renderQueue(scene, o);
    const size_t most = test::device().device().maxWorkGroup;
    for (int group : {16, 32, 128, 256}) {
        if (size_t(group) > most) continue;
        RenderOptions g = o;
        setQueueGroup(g, group);
        const OccupancyFrame f = renderQueue(scene, g);
        EXPECT_TRUE(test::sameBits(base.image, f.image)) << "--queue-group " << group;
        EXPECT_EQ(base.stats.rays, f.stats.rays) << "--queue-group " << group;
    }
}

TEST(QueueOccupancy, LocalPadKeepsTheBitsAndReachesTheStageKernels) {
    const Scene scene = occupancyWall();
    const RenderOptions o = occupancyOptions(scene);
    const OccupancyFrame base = renderQueue(scene, o);
    const size_t pad = 4096;
    if (pad * 2 > test::device().device().localMem) GTEST_SKIP() << "too little local memory";
    RenderOptions padded = o;
    setQueueLocalPad(padded, pad);
    const OccupancyFrame f = renderQueue(scene, padded);
    EXPECT_TRUE(test::sameBits(base.image, f.image));
    EXPECT_EQ(base.stats.rays, f.stats.rays);
    // Where the device says what a group's local memory is, the stage kernels have the pad on
    // top of their own arrays, and the bookkeeping kernels do not.
    if (localBytes(base.stats, "Queue_Extend") < 0) GTEST_SKIP() << "no CL_KERNEL_LOCAL_MEM_SIZE";
    for (const char* kernel : {"Queue_Extend", "Queue_Shadow", "Queue_ShadeGlass"})
        EXPECT_GE(localBytes(f.stats, kernel) - localBytes(base.stats, kernel), double(pad))
            << kernel;
    EXPECT_EQ(localBytes(f.stats, "Queue_Compact"), localBytes(base.stats, "Queue_Compact"));
}

TEST(QueueOccupancy, SizesTheDeviceCannotTakeAreRefusedByName) {
    const Scene scene = occupancyWall();
    const RenderOptions o = occupancyOptions(scene);
    const DeviceInfo& dev = test::device().device();
    auto refusal = [&](const RenderOptions& asked) {
        QueuePipeline queue(test::device());
        try {
            queue.render(scene, asked);
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), FailureKind::InvalidOption) << e.what();
            return std::string(e.what());
        }
        return std::string("rendered");
    };
    RenderOptions odd = o;
    setQueueGroup(odd, 48);
    EXPECT_EQ(refusal(odd), "--queue-group 48: must be a power of two");
    if (dev.maxWorkGroup < 1024) {
        RenderOptions big = o;
        setQueueGroup(big, int(dev.maxWorkGroup) * 2);
        EXPECT_NE(refusal(big).find("runs at most " + std::to_string(dev.maxWorkGroup)),
                  std::string::npos);
    }
    RenderOptions full = o;
    setQueueLocalPad(full, size_t(dev.localMem));
    const std::string why = refusal(full);
    EXPECT_EQ(why.rfind("--queue-local-pad " + std::to_string(dev.localMem) + ": ", 0), 0u) << why;
    EXPECT_NE(why.find("bytes of local memory"), std::string::npos) << why;
}

}  // namespace
}  // namespace rt
