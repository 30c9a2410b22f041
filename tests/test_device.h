// rtlab tests — the OpenCL device the tests run on: $RTLAB_DEVICE, else the first CPU (PoCL), so
// that CI and a developer's GPU machine both run the suite unchanged.
#pragma once

#include <cstdlib>
#include <memory>

#include "core/cl_runtime.h"

namespace rt::test {

inline ClContext& device() {
    static std::unique_ptr<ClContext> ctx = [] {
        const char* env = std::getenv("RTLAB_DEVICE");
        std::string spec = env && *env ? env : "";
        if (spec.empty())
            for (const DeviceInfo& d : listDevices())
                if (d.type == "CPU") return std::make_unique<ClContext>(d);
        return std::make_unique<ClContext>(selectDevice(spec));
    }();
    return *ctx;
}

}  // namespace rt::test
