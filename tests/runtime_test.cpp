// The OpenCL runtime: program cache, build logs, error names, checked allocations, device choice.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/kernel.h"
#include "core/kernel_sources.h"
#include "scratch_dir.h"
#include "test_device.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

TEST(Runtime, ErrorNames) {
    EXPECT_STREQ(clErrorName(CL_OUT_OF_RESOURCES), "CL_OUT_OF_RESOURCES");
    EXPECT_STREQ(clErrorName(CL_INVALID_WORK_GROUP_SIZE), "CL_INVALID_WORK_GROUP_SIZE");
    EXPECT_STREQ(clErrorName(-9999), "CL_UNKNOWN_ERROR");
    try {
        throwClError(cl::Error(CL_MEM_OBJECT_ALLOCATION_FAILURE, "clCreateBuffer"), "allocating x");
        FAIL();
    } catch (const Error& e) {
        EXPECT_STREQ(
            e.what(),
            "allocating x: clCreateBuffer failed with CL_MEM_OBJECT_ALLOCATION_FAILURE (-4)");
    }
}

// Out-of-memory errors from a launch carry what the frame needed; other errors do not.
TEST(Runtime, OutOfMemoryErrorsCarryTheHint) {
    for (cl_int code :
         {CL_OUT_OF_RESOURCES, CL_OUT_OF_HOST_MEMORY, CL_MEM_OBJECT_ALLOCATION_FAILURE}) {
        try {
            throwClError(cl::Error(code, "clEnqueueNDRangeKernel"), "frame", "lower --bounces");
            FAIL();
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()),
                      std::string("frame: clEnqueueNDRangeKernel failed with ") +
                          clErrorName(code) + " (" + std::to_string(code) + "); lower --bounces");
        }
    }
    try {
        throwClError(cl::Error(CL_INVALID_KERNEL_ARGS, "clEnqueueNDRangeKernel"), "frame",
                     "lower --bounces");
        FAIL();
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "frame: clEnqueueNDRangeKernel failed with CL_INVALID_KERNEL_ARGS (-52)");
    }
}

TEST(Runtime, RepeatBuildsComeFromTheCache) {
    fs::path dir = rt::test::scratchPath("cache");
    setenv("RTLAB_CACHE_DIR", dir.c_str(), 1);
    DeviceInfo d = test::device().device();
    // A macro defined twice: a compiler warning, so that the build log has something to keep.
    const std::vector<std::string> defines = {"RT_HAS_TRIANGLES", "RT_LOG_PROBE=1",
                                              "RT_LOG_PROBE=2"};
    std::string log;  // the source build's
    {
        ClContext cl(d);
        cl.program("probe.cl", defines);
        EXPECT_EQ(cl.lastProgramSource(), "built");
        log = cl.lastBuildLog();
        // PoCL's clang says so; another compiler may keep quiet, and the checks below still
        // hold, if with less to compare.
        if (d.platformName == "Portable Computing Language")
            EXPECT_NE(log.find("RT_LOG_PROBE"), std::string::npos) << log;
        cl.program("probe.cl", defines);
        EXPECT_EQ(cl.lastProgramSource(), "memory");
        EXPECT_EQ(cl.lastBuildLog(), log);
        cl.program("probe.cl", {"RT_HAS_TRIANGLES", "RT_WATERTIGHT"});  // other defines: rebuild
        EXPECT_EQ(cl.lastProgramSource(), "built");
        EXPECT_EQ(cl.lastBuildLog().find("RT_LOG_PROBE"), std::string::npos);  // its own log
    }
    // A new process would see the same: the binary is on disk with its build log (registers
    // are read from the log), or, on a device that caches its own builds, in the driver's
    // cache, and rtlab writes nothing.
    ClContext fresh(d);
    fresh.program("probe.cl", defines);
    if (d.cachesBuilds) {
        EXPECT_EQ(fresh.lastProgramSource(), "built");
        EXPECT_FALSE(fs::exists(dir) && !fs::is_empty(dir)) << "rtlab wrote binaries to " << dir;
    } else {
        EXPECT_EQ(fresh.lastProgramSource(), "disk");
    }
    EXPECT_EQ(fresh.lastBuildLog(), log);
    unsetenv("RTLAB_CACHE_DIR");
    fs::remove_all(dir);
}

TEST(Runtime, DriverProgramCacheIsOffOnceDevicesAreListed) {
    // NVIDIA's own program cache would serve a build without its register report; listing the
    // devices turns it off (CUDA_CACHE_DISABLE=1) unless the caller set the variable.
    listDevices();
    const char* v = std::getenv("CUDA_CACHE_DISABLE");
    ASSERT_NE(v, nullptr);
    EXPECT_STRNE(v, "");
}

TEST(Runtime, BuildFailureCarriesTheBuildLog) {
    // A copy of the kernel tree with a syntax error injected into intersect.cl.
    fs::path dir = rt::test::scratchPath("broken_kernels/");
    for (const EmbeddedSource& s : embeddedKernelSources()) {
        std::ofstream out(dir / s.name);
        out << s.text;
        if (std::string(s.name) == "intersect.cl") out << "\nthis is not OpenCL C;\n";
    }
    ClContext cl(test::device().device(), KernelSources(dir));
    try {
        cl.program("probe.cl", {});
        FAIL() << "the broken source built";
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("building probe.cl"), std::string::npos) << msg;
        EXPECT_NE(msg.find("CL_BUILD_PROGRAM_FAILURE"), std::string::npos) << msg;
        EXPECT_NE(msg.find("intersect.cl"), std::string::npos) << "log names the file: " << msg;
    }
    fs::remove_all(dir);
}

TEST(Runtime, KernelDirMustExist) {
    EXPECT_THROW(KernelSources("/no/such/dir"), Error);
    KernelSources embedded;
    EXPECT_THROW(embedded.file("nope.cl"), Error);
    std::string resolved = embedded.resolve("megakernel.cl");
    EXPECT_NE(resolved.find("#line 1 \"types.h\""), std::string::npos);
    EXPECT_EQ(resolved.find("#include \"raytree.cl\""), std::string::npos);
}

TEST(Runtime, AllocationsAreCheckedBeforeTheyAreMade) {
    ClContext& cl = test::device();
    size_t tooBig = size_t(cl.device().maxAlloc) + 1;
    try {
        cl.allocate(tooBig, CL_MEM_READ_WRITE, "the test buffer");
        FAIL();
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("the test buffer"), std::string::npos) << msg;
        EXPECT_NE(msg.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE"), std::string::npos) << msg;
    }
    EXPECT_NO_THROW(cl.allocate(1024, CL_MEM_READ_WRITE, "a small buffer"));
}

TEST(Runtime, DeviceSelection) {
    const char* saved = std::getenv("RTLAB_DEVICE");
    std::string restore = saved ? saved : "";
    std::vector<DeviceInfo> all = listDevices();
    ASSERT_FALSE(all.empty());
    EXPECT_EQ(selectDevice("0").name, all[0].name);
    // "cpu" and "gpu" pick a device of that type where the machine has one, and fail clearly
    // where it has none (a GPU host may list no CPU device at all).
    for (const char* type : {"cpu", "gpu"}) {
        const std::string upper = std::string(type) == "cpu" ? "CPU" : "GPU";
        const bool present = std::any_of(all.begin(), all.end(),
                                         [&](const DeviceInfo& d) { return d.type == upper; });
        if (present) {
            EXPECT_EQ(selectDevice(type).type, upper);
            setenv("RTLAB_DEVICE", type, 1);
            EXPECT_EQ(selectDevice("").type, upper);
            unsetenv("RTLAB_DEVICE");
        } else {
            EXPECT_THROW(selectDevice(type), Error) << type;
        }
    }
    EXPECT_THROW(selectDevice("12345"), Error);
    EXPECT_THROW(selectDevice("no-such-device-name"), Error);
    setenv("RTLAB_DEVICE", "no-such-device-name", 1);
    try {
        selectDevice("");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("RTLAB_DEVICE"), std::string::npos) << e.what();
    }
    if (restore.empty())
        unsetenv("RTLAB_DEVICE");
    else
        setenv("RTLAB_DEVICE", restore.c_str(), 1);
}

// Kernels take their arguments by the names the source gives them, in any order; a name the
// kernel does not have is an error that says which names it has.
TEST(Runtime, KernelArgumentsAreSetByName) {
    ClContext& cl = test::device();
    cl::Program program = cl.program("probe.cl", {"RT_HAS_TRIANGLES"});
    Kernel k(program, "Probe_TriangleHits");
    EXPECT_EQ(k.arguments(), (std::vector<std::string>{"rays", "tris", "count", "hits"}));
    EXPECT_TRUE(k.has("count"));
    EXPECT_FALSE(k.has("Count"));
    try {
        k.set("triangles", cl_int(0));
        ADD_FAILURE() << "no error for an argument the kernel does not have";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "Probe_TriangleHits has no argument 'triangles' (it takes rays, tris, "
                     "count, hits)");
    }
    try {
        Kernel missing(program, "Probe_Nothing");
        ADD_FAILURE() << "no error for a kernel the program does not have";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("Probe_Nothing"), std::string::npos) << e.what();
    }
    // Set out of order, then run: a hit at t = 1 from the one triangle in front of the ray.
    const std::vector<float> ray = {0.25f, 0.25f, -1, 0, 0, 1};
    const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    cl::Buffer rb(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, ray.size() * 4,
                  const_cast<float*>(ray.data()));
    cl::Buffer tb(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, tri.size() * 4,
                  const_cast<float*>(tri.data()));
    cl::Buffer hb(cl.context(), CL_MEM_WRITE_ONLY, 4);
    k.set("hits", hb).set("count", cl_int(1)).set("tris", tb).set("rays", rb);
    cl.queue().enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(1));
    cl_int hits = -1;
    cl.queue().enqueueReadBuffer(hb, CL_TRUE, 0, 4, &hits);
    EXPECT_EQ(hits, 1);
}

}  // namespace
}  // namespace rt
