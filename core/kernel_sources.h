// rtlab — OpenCL C sources: embedded in the binary at build time (cmake/embed_kernels.cmake), or
// read from a directory tree for development (--kernel-dir / RTLAB_KERNEL_DIR), so that a kernel
// edit needs no rebuild. `#include "name"` lines are resolved here, by file name, because the
// OpenCL compiler is given one string; each file is preceded by a #line directive so compiler
// messages name the real file and line.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace rt {

struct EmbeddedSource {
    const char* name;  // file name, e.g. "intersect.cl"
    const char* path;  // where it lives in a source checkout, e.g. "core/cl/intersect.cl"
    std::string text;
};

const std::vector<EmbeddedSource>& embeddedKernelSources();

class KernelSources {
  public:
    // Empty dir: the embedded copies. Otherwise each file is read from dir at the path it was
    // embedded from (the build knows every pipeline folder; this file names none), else from
    // dir itself.
    explicit KernelSources(std::filesystem::path dir = {});

    // The text of one file, or throws rt::Error.
    std::string file(const std::string& name) const;
    // The main file with every #include "x" expanded once (include guards still apply).
    std::string resolve(const std::string& mainFile) const;
    bool fromDisk() const { return !dir_.empty(); }

  private:
    std::filesystem::path dir_;
};

}  // namespace rt
