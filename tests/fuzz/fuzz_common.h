// rtlab fuzz targets — shared by fuzz_scene.cpp, fuzz_obj.cpp and fuzz_model.cpp: the loaders take
// paths, so each input is written to a file in a private folder; every failure must be an
// rt::Error (one clear line), anything else is a bug and aborts so that libFuzzer keeps the input.
#pragma once

#include <stdlib.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/accel.h"
#include "core/error.h"
#include "core/model_loader.h"
#include "core/scene_loader.h"

// core/model_loader.cpp's reader process, a fork of the target, resets the crash signals to their
// default action so that a crash inside assimp ends it quietly and the loader reports one line;
// ASan keeps its own handlers unless user handlers are allowed. (Without this, the reader's crash
// would run libFuzzer's death callback and leave a crash file for an input that was handled.)
extern "C" const char* __asan_default_options() { return "allow_user_segv_handler=1"; }

namespace rt::fuzz {

inline const std::filesystem::path& workDir() {
    static const std::filesystem::path dir = [] {
        // mkdtemp, not the process id: containers reuse ids, and an earlier run's folder may
        // remain. scripts/fuzz points TMPDIR at a folder of build-fuzz/ that it empties before each
        // run.
        std::string pattern =
            (std::filesystem::temp_directory_path() / "rtlab-fuzz-XXXXXX").string();
        if (!mkdtemp(pattern.data())) {
            std::perror(pattern.c_str());
            std::abort();
        }
        std::filesystem::path d = pattern;
        // Models the fuzzed scenes can name ("meshes": [{"file": "m.obj", ...}], or "m.ply").
        std::ofstream(d / "m.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                      "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";
        std::ofstream(d / "m.ply") << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                      "property float y\nproperty float z\nelement face 1\n"
                                      "property list uchar int vertex_indices\nend_header\n"
                                      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
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
    // A model that assimp never finishes fails after 5 s, before libFuzzer's 10 s per input.
    static const bool limited = (setModelReadTimeLimit(std::chrono::seconds(5)), true);
    (void)limited;
    try {
        Scene scene = loadScene(path, fakeImage);
        if (scene.spheres.size() + scene.triangles.size() <= 4096)
            for (RenderOptions::Accel a :
                 {RenderOptions::Accel::Bv, RenderOptions::Accel::Grid, RenderOptions::Accel::Bvh})
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
