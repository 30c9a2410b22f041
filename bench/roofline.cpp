// rtlab-roofline — the device's own ceilings, measured by the project rather than quoted: memory
// bandwidth (a float4 copy and a float4 saxpy over buffers far larger than any cache) and fp32
// throughput (independent FMA chains). A result set places each pipeline's frame against these
// (bytes it must move / bandwidth). Timings come from OpenCL profiling events: warm-up launches
// first, then the median of the timed ones.
//
//   rtlab-roofline [--device SPEC] [--mib N] [--repeats N] [--out FILE.json]
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/kernel.h"
#include "core/version.h"

using namespace rt;

namespace {

// Small enough to read at a glance; the probe is no part of any pipeline, so it is not among
// the embedded kernel files that --kernel-dir reloads.
const char* kSource = R"CL(
kernel void Roof_Copy(global const float4* in, global float4* out) {
    size_t i = get_global_id(0);
    out[i] = in[i];
}
kernel void Roof_Saxpy(float a, global const float4* x, global float4* y) {
    size_t i = get_global_id(0);
    y[i] = a * x[i] + y[i];
}
// 8 independent chains of float4 FMAs, ROOF_ITERATIONS deep: 2 x 4 x 8 flops per iteration.
kernel void Roof_Fma(float a, float b, global float* out) {
    float4 v0 = (float4)(get_global_id(0)), v1 = v0 + 1.0f, v2 = v0 + 2.0f, v3 = v0 + 3.0f;
    float4 v4 = v0 + 4.0f, v5 = v0 + 5.0f, v6 = v0 + 6.0f, v7 = v0 + 7.0f;
    for (int k = 0; k < ROOF_ITERATIONS; ++k) {
        v0 = fma(v0, a, b); v1 = fma(v1, a, b); v2 = fma(v2, a, b); v3 = fma(v3, a, b);
        v4 = fma(v4, a, b); v5 = fma(v5, a, b); v6 = fma(v6, a, b); v7 = fma(v7, a, b);
    }
    float4 s = v0 + v1 + v2 + v3 + v4 + v5 + v6 + v7;
    out[get_global_id(0)] = s.x + s.y + s.z + s.w;
}
)CL";
constexpr int kFmaIterations = 1024;

struct Args {
    std::string device, out;
    size_t mib = 0;  // 0: chosen from the device
    int repeats = 10, warmup = 3;
};

Args parse(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        std::string k = argv[i];
        auto value = [&]() -> std::string {
            size_t eq = k.find('=');
            if (eq != std::string::npos) {
                std::string v = k.substr(eq + 1);
                k = k.substr(0, eq);
                return v;
            }
            if (i + 1 >= argc) throw Error(k + ": needs a value (see --help)");
            return argv[++i];
        };
        if (k == "--help" || k == "-h") {
            std::puts(
                "rtlab-roofline [--device SPEC] [--mib N] [--repeats N] [--out FILE.json]\n"
                "Measures copy and saxpy bandwidth and fp32 FMA throughput with OpenCL "
                "profiling events\n(median of --repeats after 3 warm-up launches). --mib: "
                "size of each buffer [a quarter of the\nmax allocation, at most 1024 MiB].");
            std::exit(0);
        }
        if (k.rfind("--device", 0) == 0)
            a.device = value();
        else if (k.rfind("--out", 0) == 0)
            a.out = value();
        else if (k.rfind("--mib", 0) == 0)
            a.mib = std::stoul(value());
        else if (k.rfind("--repeats", 0) == 0)
            a.repeats = std::max(1, std::stoi(value()));
        else
            throw Error("unknown flag " + k + " (see --help)");
    }
    return a;
}

double medianMs(cl::CommandQueue& q, Kernel& k, size_t global, int warmup, int repeats) {
    std::vector<double> ms;
    for (int r = 0; r < warmup + repeats; ++r) {
        cl::Event e;
        q.enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(global), cl::NullRange, nullptr,
                               &e);
        e.wait();
        if (r >= warmup) ms.push_back(eventMs(e));
    }
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    try {
        Args a = parse(argc, argv);
        ClContext cl(selectDevice(a.device));
        const DeviceInfo& d = cl.device();
        size_t bytes =
            a.mib ? a.mib << 20 : std::min<size_t>(size_t(1) << 30, d.maxAlloc / 4) & ~size_t(15);
        bytes = std::min<size_t>(bytes, d.maxAlloc);
        const size_t n4 = bytes / 16;
        cl::Program program(cl.context(), kSource);
        std::string options =
            "-cl-kernel-arg-info -DROOF_ITERATIONS=" + std::to_string(kFmaIterations);
        try {
            program.build({d.device}, options.c_str());
        } catch (const cl::Error&) {
            throw Error("roofline kernels did not build: " +
                        program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(d.device));
        }
        cl::Buffer x = cl.allocate(bytes, CL_MEM_READ_WRITE, "roofline buffer x");
        cl::Buffer y = cl.allocate(bytes, CL_MEM_READ_WRITE, "roofline buffer y");
        cl.queue().enqueueFillBuffer(x, 1.0f, 0, bytes);
        cl.queue().enqueueFillBuffer(y, 2.0f, 0, bytes);
        cl.queue().finish();

        Kernel copy(program, "Roof_Copy"), saxpy(program, "Roof_Saxpy"), fma(program, "Roof_Fma");
        copy.set("in", x).set("out", y);
        saxpy.set("a", 0.5f).set("x", x).set("y", y);
        const double copyMs = medianMs(cl.queue(), copy, n4, a.warmup, a.repeats);
        const double saxpyMs = medianMs(cl.queue(), saxpy, n4, a.warmup, a.repeats);
        // Enough work-items to fill any device many times over; each writes one float.
        const size_t fmaItems = std::max<size_t>(d.computeUnits, 1) * 8192;
        fma.set("a", 0.999f).set("b", 0.001f).set("out", x);
        const double fmaMs =
            medianMs(cl.queue(), fma, std::min(fmaItems, bytes / 4), a.warmup, a.repeats);
        const double fmaFlops = double(std::min(fmaItems, bytes / 4)) * kFmaIterations * 8 * 4 * 2;

        const double copyGBs = 2.0 * double(bytes) / (copyMs * 1e6);
        const double saxpyGBs = 3.0 * double(bytes) / (saxpyMs * 1e6);
        const double tflops = fmaFlops / (fmaMs * 1e9);
        std::printf("rtlab-roofline: %s, commit %s\n", d.label().c_str(), RTLAB_COMMIT);
        std::printf("  copy   %8.1f GB/s  (2 x %zu MiB in %.3f ms)\n", copyGBs, bytes >> 20,
                    copyMs);
        std::printf("  saxpy  %8.1f GB/s  (3 x %zu MiB in %.3f ms)\n", saxpyGBs, bytes >> 20,
                    saxpyMs);
        std::printf("  fma    %8.2f TFLOP/s fp32 (%.3f ms)\n", tflops, fmaMs);
        if (!a.out.empty()) {
            nlohmann::json j = {
                {"about",
                 "bandwidth and fp32 ceilings measured by rtlab-roofline (bench/roofline.cpp): "
                 "OpenCL profiling events, median of the timed launches after warm-up"},
                {"device", d.name},
                {"platform", d.platformName},
                {"driver", d.driver},
                {"device_version", d.version},
                {"compute_units", d.computeUnits},
                {"global_mem_bytes", d.globalMem},
                {"max_alloc_bytes", d.maxAlloc},
                {"commit", RTLAB_COMMIT},
                {"buffer_bytes", bytes},
                {"repeats", a.repeats},
                {"warmup", a.warmup},
                {"copy_gb_per_s", copyGBs},
                {"copy_ms", copyMs},
                {"saxpy_gb_per_s", saxpyGBs},
                {"saxpy_ms", saxpyMs},
                {"fma_tflops", tflops},
                {"fma_ms", fmaMs},
                {"fma_iterations", kFmaIterations}};
            std::ofstream f(a.out);
            f << j.dump(2) << "\n";
            if (!f) throw Error(a.out + ": cannot write");
        }
        return 0;
    } catch (const cl::Error& e) {
        std::fprintf(stderr, "rtlab-roofline: OpenCL error in %s: %s\n", e.what(),
                     clErrorName(e.err()));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtlab-roofline: %s\n", e.what());
    }
    return 1;
}
