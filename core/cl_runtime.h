// rtlab — the OpenCL runtime: device discovery and selection, program builds with a binary cache,
// checked allocations, and errors that name the failing call and the CL error code.
#pragma once

#include <CL/opencl.hpp>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "core/kernel_sources.h"

namespace rt {

// "CL_OUT_OF_RESOURCES" for -5, etc.
const char* clErrorName(cl_int code);

// Turns a cl::Error into rt::Error: "<what>: <call> failed with CL_..." . When the error says the
// device ran out of memory or resources, `memoryHint` (what the frame needed and how to ask for
// less) follows after "; ", so that the one line tells the user what to change.
[[noreturn]] void throwClError(const cl::Error& e, const std::string& what,
                               const std::string& memoryHint = "");

struct DeviceInfo {
    int index = -1;  // position in listDevices()
    cl::Platform platform;
    cl::Device device;
    std::string platformName, name, vendor, type, version, driver, openclC;
    cl_uint computeUnits = 0;
    cl_ulong globalMem = 0, maxAlloc = 0, localMem = 0;
    size_t maxWorkGroup = 0;
    // Registers the work-items of one work-group share, where the device says (NVIDIA's
    // cl_nv_device_attribute_query); 0 elsewhere.
    cl_uint registersPerGroup = 0;
    // NVIDIA's driver: its build options (-cl-nv-*), build log and inline PTX.
    bool nvidia() const { return vendor.find("NVIDIA") != std::string::npos; }
    bool correctlyRoundedDivSqrt = false;  // supports -cl-fp32-correctly-rounded-divide-sqrt
    // The driver keeps its own cache of compiled programs, keyed by source and options (PoCL),
    // so rtlab keeps none: see ClContext::program.
    bool cachesBuilds = false;
    bool isGpu() const { return type == "GPU"; }
    std::string label() const;  // "NVIDIA H100 (NVIDIA CUDA, driver 550.54)"
};

std::vector<DeviceInfo> listDevices();

// spec: a device index or a case-insensitive name substring; empty = $RTLAB_DEVICE, else the
// first GPU, else the first CPU. Throws rt::Error naming the spec when nothing matches.
DeviceInfo selectDevice(const std::string& spec);

// Milliseconds between an event's START and END profiling counters.
double eventMs(const cl::Event& event);

class ClContext {
  public:
    explicit ClContext(const DeviceInfo& device, KernelSources sources = KernelSources());

    const DeviceInfo& device() const { return device_; }
    cl::Context& context() { return context_; }
    cl::CommandQueue& queue() { return queue_; }

    // Builds mainFile with the given -D defines. Programs are cached in memory and on disk
    // ($RTLAB_CACHE_DIR, else ~/.cache/rtlab) keyed by device, driver, source text and options,
    // so a repeat run does not rebuild; on a device that caches its own builds
    // (DeviceInfo::cachesBuilds) the driver's cache stands in for the disk. On failure throws
    // rt::Error carrying the build log. `options` are further compiler options, passed as given
    // (a device's own, such as NVIDIA's -cl-nv-maxrregcount=N) and part of the cache key.
    cl::Program program(const std::string& mainFile, const std::vector<std::string>& defines,
                        const std::vector<std::string>& options = {});
    // How the last program() call was satisfied: "memory", "disk" or "built".
    const std::string& lastProgramSource() const { return lastSource_; }
    // The build log of the last program() call's program: its source build's, also when it came
    // from memory or from a binary on disk (kept beside it; empty for a binary cached without).
    const std::string& lastBuildLog() const { return lastLog_; }
    // Every program() call so far, by how it was satisfied, and the wall time spent in builds
    // and binary loads: what a frame's host time holds besides the frame.
    struct ProgramCounts {
        int built = 0, fromDisk = 0, fromMemory = 0;
        double ms = 0;
    };
    const ProgramCounts& programCounts() const { return counts_; }
    // The program being compiled from source right now ("megakernel.cl for NVIDIA H200"), or
    // empty. Safe to call from another thread: a watchdog tells a stuck compiler from a stuck
    // device by it.
    std::string building() const;
    // Source builds that take longer than half a second print "compiling FILE for DEVICE ..."
    // and then their time on stderr (off by default; front ends turn it on, so that a cold first
    // run is not silent and a warm one not noisy).
    static void announceBuilds(bool on) { announce_ = on; }

    // Checks size against CL_DEVICE_MAX_MEM_ALLOC_SIZE and the global memory left before
    // allocating; `what` names the buffer in the error. Zero bytes allocates a 16-byte stub.
    cl::Buffer allocate(size_t bytes, cl_mem_flags flags, const std::string& what);
    // Bytes this context has allocated and not yet released (released buffers are not tracked).
    void release(size_t bytes) { allocated_ -= bytes < allocated_ ? bytes : allocated_; }
    size_t allocatedBytes() const { return allocated_; }

  private:
    DeviceInfo device_;
    KernelSources sources_;
    cl::Context context_;
    cl::CommandQueue queue_;
    std::map<std::string, cl::Program> programs_;
    std::map<std::string, std::string> logs_;  // build logs, by the key of programs_
    std::string lastSource_, lastLog_;
    ProgramCounts counts_;
    size_t allocated_ = 0;
    mutable std::mutex buildingLock_;
    std::string building_;
    static inline std::atomic<bool> announce_{false};
};

}  // namespace rt
