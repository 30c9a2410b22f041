// rtlab fuzz targets — shared by fuzz_scene.cpp and fuzz_obj.cpp: the loaders take paths, so each
// input is written to a file in a private folder; every failure must be an rt::Error (one clear
// line), anything else is a bug and aborts so that libFuzzer keeps the input.
#pragma once

#include <stdlib.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/accel.h"
#include "core/error.h"
#include "core/scene_loader.h"

namespace rt::fuzz {

inline const std::filesystem::path& workDir() {
    static const std::filesystem::path dir = [] {
        // mkdtemp, not the process id: containers reuse ids, and an earlier run's folder may remain.
        // scripts/fuzz points TMPDIR at a folder of build-fuzz/ that it empties before each run.
        std::string pattern = (std::filesystem::temp_directory_path() / "rtlab-fuzz-XXXXXX").string();
        if (!mkdtemp(pattern.data())) {
            std::perror(pattern.c_str());
            std::abort();
        }
        std::filesystem::path d = pattern;
        // A model the fuzzed scenes can name ("meshes": [{"file": "m.obj", ...}]).
        std::ofstream(d / "m.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                      "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";
        return d;
    }();
    return dir;
}

inline std::filesystem::path writeInput(const char* name, const uint8_t* data, size_t size) {
    std::filesystem::path p = workDir() / name;
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return p;
}

// Cubemap faces: a 2x2 grey image for any name, so fuzzed cubemaps reach the size checks.
inline Image fakeImage(const std::filesystem::path&) {
    Image img(2, 2);
    for (float& v : img.rgb) v = 0.5f;
    return img;
}

// Loads a scene and builds every acceleration structure over it, as a render would.
inline void loadAndBuild(const std::filesystem::path& path) {
    try {
        Scene scene = loadScene(path, fakeImage);
        if (scene.spheres.size() + scene.triangles.size() <= 4096)
            for (RenderOptions::Accel a : {RenderOptions::Accel::Bv, RenderOptions::Accel::Grid,
                                           RenderOptions::Accel::Bvh})
                buildAccel(scene, a);
    } catch (const Error& e) {
        if (std::string(e.what()).find('\n') != std::string::npos) {
            std::fprintf(stderr, "multi-line error: %s\n", e.what());
            std::abort();
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "not an rt::Error: %s\n", e.what());
        std::abort();
    }
}

}  // namespace rt::fuzz
