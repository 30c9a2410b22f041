// rtlab — what a built program's kernels cost the device per work-item (the crossover README's
// "Why, measured"): registers and spill bytes from NVIDIA's build log (programs are built with
// -cl-nv-verbose on NVIDIA, core/cl_runtime.cpp), and private memory from
// CL_KERNEL_PRIVATE_MEM_SIZE everywhere (on PoCL the per-work-item stack the kernel needs).
#pragma once

#include <map>
#include <string>

#include "core/cl_runtime.h"

namespace rt {

// "<Kernel>.registers", "<Kernel>.spill_stores", "<Kernel>.spill_loads", "<Kernel>.stack_bytes"
// (NVIDIA only, from `buildLog`: ClContext::lastBuildLog(), which a program loaded from a
// binary does not hold itself), "<Kernel>.private_bytes" and "<Kernel>.local_bytes" (a work-item's
// private and a work-group's local memory, every device that answers) for each kernel of the
// program. Computed once per program object and log.
std::map<std::string, double> kernelResources(const cl::Program& program, const cl::Device& device,
                                              const std::string& buildLog);

// The NVIDIA part alone, from a build log's ptxas lines (tests feed it a log by hand).
std::map<std::string, double> parsePtxasLog(const std::string& log);

}  // namespace rt
