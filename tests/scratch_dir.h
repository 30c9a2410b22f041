// A folder that belongs to one test process: made by mkdtemp(3) under the test temp folder
// (TEST_TMPDIR, else TMPDIR, else /tmp) and removed, with everything in it, when the process
// ends. CTest runs the cases in parallel, CI may run two suites at once on one machine, and a
// container reuses process ids from one run to the next, so a name built from getpid() can
// meet a file an earlier run left behind; mkdtemp's names cannot.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace rt::test {

class ScratchDir {
  public:
    ScratchDir() {
        std::string pattern =
            (std::filesystem::path(::testing::TempDir()) / "rtlab_XXXXXX").string();
        if (!mkdtemp(pattern.data()))
            throw std::runtime_error(pattern +
                                     ": cannot make a scratch folder: " + std::strerror(errno));
        path_ = pattern;
    }
    ~ScratchDir() {
        std::error_code ignored;  // a child may still hold a file open; nothing to report at exit
        std::filesystem::remove_all(path_, ignored);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
};

// This process's scratch folder, made on first use.
inline const std::filesystem::path& scratchDir() {
    static const ScratchDir dir;
    return dir.path();
}

// `name` inside the scratch folder; with a trailing '/', a sub-folder that now exists.
inline std::string scratchPath(const std::string& name) {
    std::filesystem::path p = scratchDir() / name;
    if (!name.empty() && name.back() == '/') std::filesystem::create_directories(p);
    return p.string();
}

}  // namespace rt::test
