// rtlab — per-kernel registers, spills and private memory of a built program (see the header).
#include "core/kernel_resources.h"

#include <regex>
#include <sstream>

namespace rt {

// ptxas -v prints, per entry function:
//   ptxas info    : Compiling entry function 'Megakernel_Render' for 'sm_90'
//   ptxas info    : Function properties for Megakernel_Render
//       0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads
//   ptxas info    : Used 122 registers, 448 bytes cmem[0]
std::map<std::string, double> parsePtxasLog(const std::string& log) {
    static const std::regex entry(R"(Compiling entry function '([A-Za-z0-9_]+)')");
    static const std::regex frame(
        R"((\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads)");
    static const std::regex regs(R"(Used (\d+) registers)");
    std::map<std::string, double> out;
    std::istringstream in(log);
    std::string line, current;
    std::smatch m;
    while (std::getline(in, line)) {
        if (std::regex_search(line, m, entry)) {
            current = m[1];
        } else if (!current.empty() && std::regex_search(line, m, frame)) {
            out[current + ".stack_bytes"] = std::stod(m[1]);
            out[current + ".spill_stores"] = std::stod(m[2]);
            out[current + ".spill_loads"] = std::stod(m[3]);
        } else if (!current.empty() && std::regex_search(line, m, regs)) {
            out[current + ".registers"] = std::stod(m[1]);
        }
    }
    return out;
}

std::map<std::string, double> kernelResources(const cl::Program& program, const cl::Device& device,
                                              const std::string& log) {
    // Keyed by the program handle: a pipeline asks every frame, the answer changes only with it.
    // The log is part of the key, so a handle the driver reuses for another program is no hit.
    static std::map<std::pair<cl_program, std::string>, std::map<std::string, double>> cache;
    const auto key = std::make_pair(program(), log);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    std::map<std::string, double> out = parsePtxasLog(log);
    try {
        std::vector<cl::Kernel> kernels;
        cl::Program(program).createKernels(&kernels);  // a handle copy: createKernels is not const
        for (cl::Kernel& k : kernels) {
            const std::string name = k.getInfo<CL_KERNEL_FUNCTION_NAME>();
            cl_ulong bytes = 0;
            if (clGetKernelWorkGroupInfo(k(), device(), CL_KERNEL_PRIVATE_MEM_SIZE, sizeof bytes,
                                         &bytes, nullptr) == CL_SUCCESS)
                out[name + ".private_bytes"] = double(bytes);
            // A work-group's local memory, which with the registers sets how many groups a
            // compute unit holds at once.
            if (clGetKernelWorkGroupInfo(k(), device(), CL_KERNEL_LOCAL_MEM_SIZE, sizeof bytes,
                                         &bytes, nullptr) == CL_SUCCESS)
                out[name + ".local_bytes"] = double(bytes);
        }
    } catch (const cl::Error&) {
        // A driver that cannot say is not an error: the row simply has fewer columns.
    }
    cache[key] = out;
    return out;
}

}  // namespace rt
