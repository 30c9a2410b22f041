// rtlab — a kernel whose arguments are set by the names its OpenCL source gives them. Every
// program is built with -cl-kernel-arg-info (ClContext::program), so the device reports each
// parameter's name; setting one that the kernel does not have, or reordering a kernel's
// parameters, is then an error or nothing at all, never a buffer bound to the wrong slot.
#pragma once

#include <CL/opencl.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace rt {

class Kernel {
  public:
    Kernel() = default;
    // Throws rt::Error naming the kernel when the program has none of that name, or when the
    // device reports no argument names.
    Kernel(const cl::Program& program, const std::string& name);

    // Sets the argument called `arg` (a buffer, a scalar, a struct passed by value or
    // cl::Local); throws rt::Error "<kernel> has no argument '<arg>' (it takes a, b, ...)".
    template <typename T>
    Kernel& set(std::string_view arg, const T& value) {
        kernel_.setArg(index(arg), value);
        return *this;
    }
    // The same for `size` bytes at `value` (a struct the host holds as bytes).
    Kernel& set(std::string_view arg, size_t size, const void* value);
    bool has(std::string_view arg) const;
    // The most work-items a work-group of this kernel may have on `device` as it was built
    // (CL_KERNEL_WORK_GROUP_SIZE): below the device's own limit where the kernel's registers or
    // private memory do not fit a larger group, or where the compiler assumed a smaller one.
    size_t maxGroup(const cl::Device& device) const;

    const std::string& name() const { return name_; }
    const std::vector<std::string>& arguments() const { return args_; }
    cl::Kernel& get() { return kernel_; }
    const cl::Kernel& get() const { return kernel_; }

  private:
    cl_uint index(std::string_view arg) const;

    cl::Kernel kernel_;
    std::string name_;
    std::vector<std::string> args_;  // parameter names in declaration order
};

}  // namespace rt
