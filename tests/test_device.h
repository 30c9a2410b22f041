// rtlab tests — the OpenCL device the tests run on: $RTLAB_DEVICE, else the first CPU (PoCL), so
// that CI and a developer's GPU machine both run the suite unchanged.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

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

// A file of the shared data folder beside the checkout (../shared/models/bunny.obj), found from
// the source tree rather than the working directory, so that the test binary can run from
// anywhere.
inline std::filesystem::path sharedFile(const std::string& relative) {
    return std::filesystem::path(RTLAB_SOURCE_DIR).parent_path() / "shared" / relative;
}

// True under CI (CI=true), where a missing shared file is a failure, not a reason to skip.
inline bool underCi() {
    const char* ci = std::getenv("CI");
    return ci && std::string(ci) == "true";
}

}  // namespace rt::test

// Skips the test when `path` is missing on a developer's machine; fails it under CI, where
// the shared data folder is always laid beside the clone.
#define RTLAB_REQUIRE_FILE(path)                                                              \
    do {                                                                                      \
        if (!std::filesystem::exists(path)) {                                                 \
            if (::rt::test::underCi()) FAIL() << (path) << " is missing (CI lays ../shared)"; \
            GTEST_SKIP() << (path) << " is missing";                                          \
        }                                                                                     \
    } while (0)
