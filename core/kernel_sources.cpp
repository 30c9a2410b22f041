#include "core/kernel_sources.h"

#include <fstream>
#include <set>
#include <sstream>

#include "core/error.h"

namespace rt {

KernelSources::KernelSources(std::filesystem::path dir) : dir_(std::move(dir)) {
    if (!dir_.empty() && !std::filesystem::is_directory(dir_))
        throw Error("--kernel-dir " + dir_.string() + ": not a directory");
}

std::string KernelSources::file(const std::string& name) const {
    if (dir_.empty()) {
        for (const EmbeddedSource& s : embeddedKernelSources())
            if (name == s.name) return s.text;
        throw Error("kernel source '" + name + "' is not embedded in this binary");
    }
    for (const char* sub : {"", "core", "core/cl", "megakernel", "wavefront", "wavefront/queue"}) {
        std::filesystem::path p = dir_ / sub / name;
        if (std::filesystem::is_regular_file(p)) {
            std::ifstream in(p, std::ios::binary);
            std::stringstream ss;
            ss << in.rdbuf();
            return ss.str();
        }
    }
    throw Error("--kernel-dir " + dir_.string() + ": kernel source '" + name + "' not found");
}

// Expands `#include "x"` recursively, each file at most once, with #line directives so that
// build logs point at the real file and line.
static void expand(const KernelSources& sources, const std::string& name,
                   std::set<std::string>& seen, std::string& out) {
    if (!seen.insert(name).second) return;
    std::istringstream in(sources.file(name));
    out += "#line 1 \"" + name + "\"\n";
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        size_t first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line.compare(first, 8, "#include") == 0) {
            size_t open = line.find('"'), close = line.rfind('"');
            if (open != std::string::npos && close > open) {
                expand(sources, line.substr(open + 1, close - open - 1), seen, out);
                out += "#line " + std::to_string(number + 1) + " \"" + name + "\"\n";
                continue;
            }
        }
        out += line;
        out += '\n';
    }
}

std::string KernelSources::resolve(const std::string& mainFile) const {
    std::set<std::string> seen;
    std::string out;
    expand(*this, mainFile, seen, out);
    return out;
}

}  // namespace rt
