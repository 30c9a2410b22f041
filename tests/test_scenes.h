// rtlab tests — generated scenes that several test files share.
#pragma once

#include <cstdlib>
#include <random>
#include <string>

#include "core/error.h"
#include "core/scene.h"
#include "core/scene_loader.h"
#include "image/image_io.h"
#include "scratch_dir.h"

namespace rt::test {

// The standard scenes of scenes/, which the equivalence and acceleration tests each cover.
inline constexpr const char* kScenes[] = {"empty",   "spheres", "shadows",
                                          "cornell", "mesh",    "envmap"};

// A standard scene by name (tests run from the source root).
inline Scene load(const std::string& name) {
    return loadScene("scenes/" + name + ".json", readImage);
}

// A soup of random spheres and triangles of mixed sizes, some overlapping, some degenerate in
// one axis (axis-aligned triangles), as a BVH and grid workout.
inline Scene soup(int spheres, int triangles, unsigned seed) {
    Scene s;
    s.name = "soup";
    dev::Material m{};
    m.opacity = m.ior = 1.f;
    s.materials = {m};
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> pos(-20.f, 20.f), size(0.01f, 1.5f);
    for (int i = 0; i < spheres; ++i)
        s.spheres.push_back({{pos(rng), pos(rng), pos(rng)}, size(rng), 0, {0, 0, 0}});
    for (int i = 0; i < triangles; ++i) {
        dev::Float3 a{pos(rng), pos(rng), pos(rng)};
        float d = size(rng);
        dev::Float3 b{a.x + d, a.y, a.z}, c{a.x, a.y + (i % 3 ? d : 0.f), a.z + d};
        dev::Float3 n{0, 0, 1};
        s.triangles.push_back({a, b, c, n, n, n, 0, 0});
    }
    finalizeScene(s);
    return s;
}

// A wall of the crossover map (scripts/make-map.py) of spheres `size` px across in a frame of
// `frame` (WxH), of 16 materials at random, `special` of them mirrors or glass, the patterns at
// `octaves` noise octaves: written to a scratch folder of its own and loaded.
inline Scene mapWall(int size, const std::string& special, int octaves, const std::string& frame) {
    const std::string dir = scratchPath("map-wall/");
    const std::string cmd = "python3 scripts/make-map.py --out " + dir + " --size " +
                            std::to_string(size) + " --special " + special + " --octaves " +
                            std::to_string(octaves) + " --materials 16 --frame " + frame +
                            " > /dev/null";
    if (std::system(cmd.c_str()) != 0) throw Error("failed: " + cmd);
    const std::string percent = std::to_string(int(std::stod(special) * 100 + 0.5));
    return loadScene(dir + "map-s" + std::to_string(size) + "-x" + percent + "-o" +
                         std::to_string(octaves) + "-m16-f" + frame + ".json",
                     readImage);
}

}  // namespace rt::test
