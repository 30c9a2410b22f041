// rtlab — kernels with named arguments (kernel.h).
#include "core/kernel.h"

#include <algorithm>
#include <cstdlib>

#include "core/cl_runtime.h"
#include "core/error.h"

namespace rt {

Kernel::Kernel(const cl::Program& program, const std::string& name) : name_(name) {
    try {
        kernel_ = cl::Kernel(program, name.c_str());
    } catch (const cl::Error& e) {
        throw Error("kernel " + name + ": clCreateKernel failed with " + clErrorName(e.err()),
                    FailureKind::OpenCl);
    }
    const cl_uint count = kernel_.getInfo<CL_KERNEL_NUM_ARGS>();
    args_.reserve(count);
    for (cl_uint i = 0; i < count; ++i) {
        cl_int err = CL_SUCCESS;
        std::string arg;
        try {
            arg = kernel_.getArgInfo<CL_KERNEL_ARG_NAME>(i, &err);
        } catch (const cl::Error& e) {
            err = e.err();
        }
        if (err != CL_SUCCESS)
            throw Error("kernel " + name + ": the device reports no name for argument " +
                            std::to_string(i) + " (" + clErrorName(err) +
                            "); was the program built without -cl-kernel-arg-info?",
                        FailureKind::OpenCl);
        args_.push_back(arg.c_str());  // drivers may count the terminating NUL in the size
    }
}

Kernel& Kernel::set(std::string_view arg, size_t size, const void* value) {
    kernel_.setArg(index(arg), size, value);
    return *this;
}

bool Kernel::has(std::string_view arg) const {
    return std::find(args_.begin(), args_.end(), arg) != args_.end();
}

size_t Kernel::maxGroup(const cl::Device& device) const {
    const size_t most = kernel_.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(device);
    // A test's stand-in for a GPU whose registers hold fewer work-items a group than the device's
    // own limit (tests/persistent_test.cpp): every kernel reports at most this many.
    if (const char* limit = std::getenv("RTLAB_KERNEL_GROUP_LIMIT"); limit && *limit)
        return std::min(most, size_t(std::strtoull(limit, nullptr, 10)));
    return most;
}

cl_uint Kernel::index(std::string_view arg) const {
    auto it = std::find(args_.begin(), args_.end(), arg);
    if (it != args_.end()) return cl_uint(it - args_.begin());
    std::string takes;
    for (const std::string& a : args_) takes += (takes.empty() ? "" : ", ") + a;
    throw Error(name_ + " has no argument '" + std::string(arg) + "' (it takes " + takes + ")");
}

}  // namespace rt
