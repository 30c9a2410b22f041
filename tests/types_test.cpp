// The shared records must have the same layout on the host and on the device.
#include "core/types.h"

#include <gtest/gtest.h>

#include <cstddef>

#include "core/kernel.h"
#include "test_device.h"

namespace rt {
namespace {

TEST(Types, DeviceSeesTheSameSizesAndOffsets) {
    ClContext& cl = test::device();
    cl::Program program = cl.program("probe.cl", {});
    Kernel kernel(program, "Probe_Sizes");
    constexpr int kCount = 17;
    cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, kCount * sizeof(cl_uint));
    kernel.set("out", out);
    cl.queue().enqueueNDRangeKernel(kernel.get(), cl::NullRange, cl::NDRange(1));
    cl_uint got[kCount] = {};
    cl.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof got, got);
    using namespace dev;
    const size_t expected[kCount] = {sizeof(Float3),
                                     sizeof(Material),
                                     sizeof(Sphere),
                                     sizeof(Plane),
                                     sizeof(Triangle),
                                     sizeof(MeshInstance),
                                     sizeof(Light),
                                     sizeof(Camera),
                                     sizeof(RenderSettings),
                                     sizeof(Node),
                                     sizeof(BvhNode),
                                     offsetof(Node, occluded),
                                     offsetof(RenderSettings, camera),
                                     offsetof(MeshInstance, sphereRadius),
                                     sizeof(Grid),
                                     sizeof(Kdop),
                                     offsetof(RenderSettings, grid)};
    for (int i = 0; i < kCount; ++i) EXPECT_EQ(got[i], expected[i]) << "probe entry " << i;
}

TEST(Types, NodeIsFortyEightBytes) { EXPECT_EQ(sizeof(dev::Node), 48u); }

}  // namespace
}  // namespace rt
