#include "core/cl_runtime.h"

#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "core/error.h"

namespace rt {

const char* clErrorName(cl_int code) {
    switch (code) {
#define RT_CASE(x) \
    case x:        \
        return #x;
        RT_CASE(CL_SUCCESS)
        RT_CASE(CL_DEVICE_NOT_FOUND)
        RT_CASE(CL_DEVICE_NOT_AVAILABLE)
        RT_CASE(CL_COMPILER_NOT_AVAILABLE)
        RT_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
        RT_CASE(CL_OUT_OF_RESOURCES)
        RT_CASE(CL_OUT_OF_HOST_MEMORY)
        RT_CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
        RT_CASE(CL_MEM_COPY_OVERLAP)
        RT_CASE(CL_IMAGE_FORMAT_MISMATCH)
        RT_CASE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
        RT_CASE(CL_BUILD_PROGRAM_FAILURE)
        RT_CASE(CL_MAP_FAILURE)
        RT_CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
        RT_CASE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
        RT_CASE(CL_COMPILE_PROGRAM_FAILURE)
        RT_CASE(CL_LINKER_NOT_AVAILABLE)
        RT_CASE(CL_LINK_PROGRAM_FAILURE)
        RT_CASE(CL_DEVICE_PARTITION_FAILED)
        RT_CASE(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
        RT_CASE(CL_INVALID_VALUE)
        RT_CASE(CL_INVALID_DEVICE_TYPE)
        RT_CASE(CL_INVALID_PLATFORM)
        RT_CASE(CL_INVALID_DEVICE)
        RT_CASE(CL_INVALID_CONTEXT)
        RT_CASE(CL_INVALID_QUEUE_PROPERTIES)
        RT_CASE(CL_INVALID_COMMAND_QUEUE)
        RT_CASE(CL_INVALID_HOST_PTR)
        RT_CASE(CL_INVALID_MEM_OBJECT)
        RT_CASE(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
        RT_CASE(CL_INVALID_IMAGE_SIZE)
        RT_CASE(CL_INVALID_SAMPLER)
        RT_CASE(CL_INVALID_BINARY)
        RT_CASE(CL_INVALID_BUILD_OPTIONS)
        RT_CASE(CL_INVALID_PROGRAM)
        RT_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
        RT_CASE(CL_INVALID_KERNEL_NAME)
        RT_CASE(CL_INVALID_KERNEL_DEFINITION)
        RT_CASE(CL_INVALID_KERNEL)
        RT_CASE(CL_INVALID_ARG_INDEX)
        RT_CASE(CL_INVALID_ARG_VALUE)
        RT_CASE(CL_INVALID_ARG_SIZE)
        RT_CASE(CL_INVALID_KERNEL_ARGS)
        RT_CASE(CL_INVALID_WORK_DIMENSION)
        RT_CASE(CL_INVALID_WORK_GROUP_SIZE)
        RT_CASE(CL_INVALID_WORK_ITEM_SIZE)
        RT_CASE(CL_INVALID_GLOBAL_OFFSET)
        RT_CASE(CL_INVALID_EVENT_WAIT_LIST)
        RT_CASE(CL_INVALID_EVENT)
        RT_CASE(CL_INVALID_OPERATION)
        RT_CASE(CL_INVALID_GL_OBJECT)
        RT_CASE(CL_INVALID_BUFFER_SIZE)
        RT_CASE(CL_INVALID_MIP_LEVEL)
        RT_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
        RT_CASE(CL_INVALID_PROPERTY)
        RT_CASE(CL_INVALID_IMAGE_DESCRIPTOR)
        RT_CASE(CL_INVALID_COMPILER_OPTIONS)
        RT_CASE(CL_INVALID_LINKER_OPTIONS)
        RT_CASE(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef RT_CASE
        default:
            return "CL_UNKNOWN_ERROR";
    }
}

void throwClError(const cl::Error& e, const std::string& what, const std::string& memoryHint) {
    std::ostringstream msg;
    msg << what << ": " << e.what() << " failed with " << clErrorName(e.err()) << " (" << e.err()
        << ")";
    const bool outOfMemory = e.err() == CL_OUT_OF_RESOURCES || e.err() == CL_OUT_OF_HOST_MEMORY ||
                             e.err() == CL_MEM_OBJECT_ALLOCATION_FAILURE;
    if (outOfMemory && !memoryHint.empty()) msg << "; " << memoryHint;
    throw Error(msg.str(), outOfMemory ? FailureKind::OutOfMemory : FailureKind::OpenCl);
}

std::string DeviceInfo::label() const {
    return name + " (" + platformName + ", driver " + driver + ")";
}

static std::string trim(std::string s) {
    while (!s.empty() && (s.back() == '\0' || std::isspace((unsigned char)s.back()))) s.pop_back();
    size_t i = 0;
    while (i < s.size() && std::isspace((unsigned char)s[i])) ++i;
    return s.substr(i);
}

// PoCL's CPU device runs work-groups on threads it starts when the platform is first listed, with
// the default attributes, so glibc's default stack (ulimit -s, usually 8 MiB). Its work-group
// function lays the private arrays of the 64 work-items of a group side by side: a pipeline's
// image kernel's private tree (up to kPrivateTreeLimit, 256 KiB) then needs 16 MiB, and bounce
// limits 10 and 11 crashed the process (SIGSEGV in Wavefront_Image). Threads started from here on
// get at least 64 MiB of stack (address space; pages are committed only when touched).
static void widenThreadStacks() {
    static std::once_flag once;
    std::call_once(once, [] {
        constexpr size_t kStack = size_t(64) << 20;
        pthread_attr_t attr;
        if (pthread_getattr_default_np(&attr) != 0) return;
        size_t size = 0;
        if (pthread_attr_getstacksize(&attr, &size) == 0 && size < kStack &&
            pthread_attr_setstacksize(&attr, kStack) == 0)
            pthread_setattr_default_np(&attr);
        pthread_attr_destroy(&attr);
    });
}

// NVIDIA's driver keeps a cache of its own of compiled programs (~/.nv/ComputeCache), and a
// program it serves from there comes without the compiler's -cl-nv-verbose report, where
// registers and spills are read (kernel_resources.h). A program that another process had built
// first (the GPU smoke check and a sweep keep separate caches of rtlab's own) was then measured
// without its registers. rtlab's own cache (ClContext::program) keeps each binary with the log
// of the build that made it, so the driver's cache is turned off, unless CUDA_CACHE_DISABLE is
// set already. The driver reads it when the platform is first listed.
static void disableDriverProgramCache() { setenv("CUDA_CACHE_DISABLE", "1", /*overwrite=*/0); }

// NVIDIA's cl_nv_device_attribute_query: the registers a work-group's work-items share
// (CL_DEVICE_REGISTERS_PER_BLOCK_NV, 65,536 on the H200), or 0 where the device does not say.
static cl_uint registersPerGroup(const cl::Device& d) {
    if (d.getInfo<CL_DEVICE_EXTENSIONS>().find("cl_nv_device_attribute_query") == std::string::npos)
        return 0;
    try {
        return d.getInfo<CL_DEVICE_REGISTERS_PER_BLOCK_NV>();
    } catch (const cl::Error&) {
        return 0;
    }
}

std::vector<DeviceInfo> listDevices() {
    std::vector<DeviceInfo> out;
    std::vector<cl::Platform> platforms;
    widenThreadStacks();
    disableDriverProgramCache();
    try {
        cl::Platform::get(&platforms);
    } catch (const cl::Error& e) {
        if (e.err() == CL_PLATFORM_NOT_FOUND_KHR) return out;
        throwClError(e, "listing OpenCL platforms");
    }
    for (cl::Platform& p : platforms) {
        std::vector<cl::Device> devices;
        try {
            p.getDevices(CL_DEVICE_TYPE_ALL, &devices);
        } catch (const cl::Error&) {
            continue;  // a platform without devices is not an error
        }
        for (cl::Device& d : devices) {
            DeviceInfo info;
            info.index = int(out.size());
            info.platform = p;
            info.device = d;
            info.platformName = trim(p.getInfo<CL_PLATFORM_NAME>());
            info.name = trim(d.getInfo<CL_DEVICE_NAME>());
            info.vendor = trim(d.getInfo<CL_DEVICE_VENDOR>());
            cl_device_type t = d.getInfo<CL_DEVICE_TYPE>();
            info.type = (t & CL_DEVICE_TYPE_GPU)           ? "GPU"
                        : (t & CL_DEVICE_TYPE_CPU)         ? "CPU"
                        : (t & CL_DEVICE_TYPE_ACCELERATOR) ? "ACCELERATOR"
                                                           : "OTHER";
            info.version = trim(d.getInfo<CL_DEVICE_VERSION>());
            info.driver = trim(d.getInfo<CL_DRIVER_VERSION>());
            info.openclC = trim(d.getInfo<CL_DEVICE_OPENCL_C_VERSION>());
            info.computeUnits = d.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
            info.globalMem = d.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
            info.maxAlloc = d.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
            info.localMem = d.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
            info.maxWorkGroup = d.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
            info.registersPerGroup = registersPerGroup(d);
            info.correctlyRoundedDivSqrt = (d.getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() &
                                            CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
            // PoCL caches every build by source and options ($POCL_CACHE_DIR), and compiles a
            // kernel for each work-group size it is launched with, on the first launch. Asked
            // for a program binary, it first compiles every kernel of the program once more for
            // any work-group size, and a program made from that binary is new to its cache, so
            // its launches compile again: a disk cache of binaries would triple the work.
            info.cachesBuilds = info.platformName == "Portable Computing Language";
            out.push_back(info);
        }
    }
    return out;
}

static std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

DeviceInfo selectDevice(const std::string& requested) {
    std::string spec = requested;
    std::string source = "--device";
    if (spec.empty()) {
        if (const char* env = std::getenv("RTLAB_DEVICE"); env && *env) {
            spec = env;
            source = "RTLAB_DEVICE";
        }
    }
    std::vector<DeviceInfo> devices = listDevices();
    if (devices.empty())
        throw Error("no OpenCL device found: is an ICD installed (scripts/setup installs PoCL)?");
    if (spec.empty()) {
        for (const DeviceInfo& d : devices)
            if (d.isGpu()) return d;
        for (const DeviceInfo& d : devices)
            if (d.type == "CPU") return d;
        return devices.front();
    }
    bool numeric =
        std::all_of(spec.begin(), spec.end(), [](unsigned char c) { return std::isdigit(c); });
    if (numeric) {
        size_t i = std::stoul(spec);
        if (i < devices.size()) return devices[i];
        throw Error(source + " " + spec + ": no such device index (there are " +
                    std::to_string(devices.size()) + "; see `rtlab devices`)");
    }
    for (const DeviceInfo& d : devices)  // "cpu" / "gpu": the first device of that type
        if (lower(d.type) == lower(spec)) return d;
    if (lower(spec) == "gpu" || lower(spec) == "cpu") {
        std::string have;
        for (const DeviceInfo& d : devices)
            have += (have.empty() ? "" : ", ") + d.name + " [" + d.type + "]";
        throw Error(source + " " + spec + ": no " + (lower(spec) == "gpu" ? "GPU" : "CPU") +
                    " device found (OpenCL sees: " + have + ")");
    }
    for (const DeviceInfo& d : devices)
        if (lower(d.name).find(lower(spec)) != std::string::npos ||
            lower(d.platformName).find(lower(spec)) != std::string::npos)
            return d;
    throw Error(source + " '" + spec +
                "': no device name or platform matches (see `rtlab devices`)");
}

double eventMs(const cl::Event& event) {
    cl_ulong start = event.getProfilingInfo<CL_PROFILING_COMMAND_START>();
    cl_ulong end = event.getProfilingInfo<CL_PROFILING_COMMAND_END>();
    return double(end - start) * 1e-6;
}

ClContext::ClContext(const DeviceInfo& device, KernelSources sources)
    : device_(device), sources_(std::move(sources)) {
    try {
        context_ = cl::Context(device_.device);
        queue_ = cl::CommandQueue(context_, device_.device, CL_QUEUE_PROFILING_ENABLE);
    } catch (const cl::Error& e) {
        throwClError(e, "creating a context on " + device_.label());
    }
}

namespace {

// Prints "compiling WHAT ..." on stderr once a build has run for half a second: a cold build
// takes seconds and should not be silent, while a driver's warm cache answers in milliseconds
// and has nothing to announce.
class SlowBuildNotice {
  public:
    explicit SlowBuildNotice(std::string what)
        : what_(std::move(what)), thread_([this] {
              std::unique_lock<std::mutex> hold(lock_);
              if (!wake_.wait_for(hold, std::chrono::milliseconds(500), [this] { return done_; })) {
                  std::fprintf(stderr, "compiling %s ...\n", what_.c_str());
                  std::fflush(stderr);
                  printed_ = true;
              }
          }) {}
    ~SlowBuildNotice() { finish(); }
    SlowBuildNotice(const SlowBuildNotice&) = delete;
    SlowBuildNotice& operator=(const SlowBuildNotice&) = delete;
    // Ends the wait; true when the notice was printed (so the caller reports the build's time).
    bool finish() {
        {
            std::lock_guard<std::mutex> hold(lock_);
            done_ = true;
        }
        wake_.notify_one();
        if (thread_.joinable()) thread_.join();
        return printed_;
    }

  private:
    std::string what_;
    std::mutex lock_;
    std::condition_variable wake_;
    bool done_ = false, printed_ = false;
    std::thread thread_;  // last: it starts once the members above exist
};

}  // namespace

static uint64_t fnv1a(const std::string& s, uint64_t h = 1469598103934665603ull) {
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
    return h;
}

static std::filesystem::path cacheDir() {
    if (const char* d = std::getenv("RTLAB_CACHE_DIR"); d && *d) return d;
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
        return std::filesystem::path(x) / "rtlab";
    if (const char* h = std::getenv("HOME"); h && *h)
        return std::filesystem::path(h) / ".cache" / "rtlab";
    return {};
}

cl::Program ClContext::program(const std::string& mainFile, const std::vector<std::string>& defines,
                               const std::vector<std::string>& extraOptions) {
    // Argument names (rt::Kernel sets arguments by name); they change no generated code.
    std::string options = "-cl-std=CL1.2 -cl-kernel-arg-info";
    // OpenCL lets float division and sqrt be 2.5-3 ulp; NVIDIA's compiler then picks different
    // approximations in different kernels, and the pipelines' images drift apart where they
    // must agree bit for bit. Correct rounding makes them bit-identical again at no measurable
    // cost.
    if (device_.correctlyRoundedDivSqrt) options += " -cl-fp32-correctly-rounded-divide-sqrt";
    for (const std::string& d : defines) options += " -D" + d;
    for (const std::string& x : extraOptions) options += " " + x;
    // Kernels pick the cheaper form of a few operations per kind of device (core/cl/accel.cl).
    if (device_.type == "CPU") options += " -DRT_DEVICE_CPU";
    // Registers and spills per kernel in the build log (core/kernel_resources.h).
    if (device_.nvidia()) options += " -cl-nv-verbose";
    // Extra compiler options for experiments (e.g. -cl-fast-relaxed-math); part of the cache key.
    if (const char* extra = std::getenv("RTLAB_CL_OPTIONS"); extra && *extra)
        options += std::string(" ") + extra;
    std::string source = sources_.resolve(mainFile);
    std::string key = device_.name + "|" + device_.platformName + "|" + device_.driver + "|" +
                      options + "|" + source;
    if (auto it = programs_.find(key); it != programs_.end()) {
        lastSource_ = "memory";
        lastLog_ = logs_[key];
        ++counts_.fromMemory;
        return it->second;
    }
    const auto start = std::chrono::steady_clock::now();
    auto spent = [&] {
        counts_.ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
    };
    char hash[32];
    std::snprintf(hash, sizeof hash, "%016llx", (unsigned long long)fnv1a(key));
    std::filesystem::path dir = device_.cachesBuilds ? std::filesystem::path() : cacheDir();
    std::filesystem::path file = dir.empty() ? dir : dir / (std::string(hash) + ".bin");
    // The source build's log goes beside the binary: a program loaded from a binary has none of
    // its own, and the log is where NVIDIA's registers and spills are read (kernel_resources.h).
    std::filesystem::path logFile = file.empty() ? file : dir / (std::string(hash) + ".log");
    auto buildLog = [&](cl::Program& p) {
        try {
            return p.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device_.device);
        } catch (const cl::Error&) {
            return std::string("(no build log)");
        }
    };

    // Disk cache: a stale or foreign binary simply falls back to a source build.
    if (!file.empty() && !sources_.fromDisk()) {
        std::ifstream in(file, std::ios::binary);
        if (in) {
            std::vector<unsigned char> bin((std::istreambuf_iterator<char>(in)), {});
            try {
                cl::Program::Binaries bins{bin};
                cl::Program p(context_, {device_.device}, bins);
                p.build({device_.device}, options.c_str());
                std::ifstream logIn(logFile, std::ios::binary);
                logs_[key] = lastLog_ = std::string(std::istreambuf_iterator<char>(logIn), {});
                programs_[key] = p;
                lastSource_ = "disk";
                ++counts_.fromDisk;
                spent();
                return p;
            } catch (const cl::Error&) {
            }
        }
    }

    cl::Program p;
    const std::string what = mainFile + " for " + device_.name;
    {
        std::lock_guard<std::mutex> hold(buildingLock_);
        building_ = what;
    }
    struct Done {  // clears building_ however the build ends
        ClContext& cl;
        ~Done() {
            std::lock_guard<std::mutex> hold(cl.buildingLock_);
            cl.building_.clear();
        }
    } done{*this};
    std::optional<SlowBuildNotice> notice;
    if (announce_) notice.emplace(what);
    try {
        p = cl::Program(context_, source);
        p.build({device_.device}, options.c_str());
        if (notice && notice->finish()) {
            size_t kernels = 0;
            try {
                kernels = p.getInfo<CL_PROGRAM_NUM_KERNELS>();
            } catch (const cl::Error&) {
            }
            std::fprintf(
                stderr, "compiled %s (%zu kernels) in %.1f s\n", mainFile.c_str(), kernels,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }
    } catch (const cl::Error& e) {
        std::string log = buildLog(p);
        throw Error("building " + mainFile + " for " + device_.name + " failed with " +
                        clErrorName(e.err()) + " (options: " + options + ")\n" + log,
                    FailureKind::OpenCl);
    }
    programs_[key] = p;
    logs_[key] = lastLog_ = buildLog(p);
    lastSource_ = "built";
    ++counts_.built;
    if (!file.empty()) {
        try {
            auto bins = p.getInfo<CL_PROGRAM_BINARIES>();
            if (!bins.empty() && !bins[0].empty()) {
                std::error_code ec;
                std::filesystem::create_directories(dir, ec);
                // The log first: a process that finds the binary finds its log. One temporary
                // file per process and thread: sweeps on several devices (and shards on one
                // machine) build the same program at the same moment.
                auto write = [&](const std::filesystem::path& to, const char* bytes, size_t n) {
                    std::filesystem::path tmp = to;
                    tmp +=
                        "." + std::to_string(getpid()) + "-" +
                        std::to_string(std::hash<std::thread::id>()(std::this_thread::get_id())) +
                        ".tmp";
                    std::ofstream out(tmp, std::ios::binary);
                    out.write(bytes, std::streamsize(n));
                    out.close();
                    if (out) std::filesystem::rename(tmp, to, ec);
                };
                write(logFile, lastLog_.data(), lastLog_.size());
                write(file, reinterpret_cast<const char*>(bins[0].data()), bins[0].size());
            }
        } catch (const cl::Error&) {
        }
    }
    spent();
    return p;
}

std::string ClContext::building() const {
    std::lock_guard<std::mutex> hold(buildingLock_);
    return building_;
}

static std::string mib(double bytes) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.1f MiB", bytes / (1024.0 * 1024.0));
    return buf;
}

cl::Buffer ClContext::allocate(size_t bytes, cl_mem_flags flags, const std::string& what) {
    if (bytes > device_.maxAlloc)
        throw Error(what + " needs " + mib(double(bytes)) + " in one buffer, but " + device_.name +
                        " allows at most " + mib(double(device_.maxAlloc)) +
                        " per allocation (CL_DEVICE_MAX_MEM_ALLOC_SIZE)",
                    FailureKind::OutOfMemory);
    if (allocated_ + bytes > device_.globalMem)
        throw Error(what + " needs " + mib(double(bytes)) + " but only " +
                        mib(double(device_.globalMem - allocated_)) + " of " + device_.name +
                        "'s global memory is left",
                    FailureKind::OutOfMemory);
    try {
        // Fault injection (tests/stability_test.cpp): RTLAB_FAIL_ALLOC_AFTER=n fails
        // every allocation that would take this context past n bytes, as a driver would.
        if (const char* limit = std::getenv("RTLAB_FAIL_ALLOC_AFTER"))
            if (*limit && allocated_ + bytes > std::strtoull(limit, nullptr, 10))
                throw cl::Error(CL_MEM_OBJECT_ALLOCATION_FAILURE, "clCreateBuffer");
        cl::Buffer b(context_, flags, std::max<size_t>(bytes, 16));
        allocated_ += bytes;
        return b;
    } catch (const cl::Error& e) {
        throwClError(e, "allocating " + what + " (" + mib(double(bytes)) + ")");
    }
}

}  // namespace rt
