// rtlab — a scene and its copy scaled about the origin: every length is multiplied by
// s (positions, radii, plane offsets, vertices, lights, the camera), directions and colours are
// kept, so that in exact arithmetic the scaled copy renders the same image. The scale-invariance
// tests and the stability report's scale sweep render both and count the pixels that differ.
#pragma once

#include "core/scene.h"
#include "core/scene_loader.h"

namespace rt {

inline Scene scaleScene(Scene scene, double s) {
    auto len = [s](float v) { return float(double(v) * s); };
    auto pos = [&](dev::Float3& p) { p = {len(p.x), len(p.y), len(p.z)}; };
    pos(scene.camera.position);
    for (dev::Sphere& sp : scene.spheres) {
        pos(sp.center);
        sp.radius = len(sp.radius);
    }
    for (dev::Plane& pl : scene.planes) pl.offset = len(pl.offset);
    for (dev::Triangle& t : scene.triangles) {
        pos(t.v0);
        pos(t.v1);
        pos(t.v2);
    }
    for (dev::Light& l : scene.lights) {
        pos(l.position);
        l.radius = len(l.radius);
    }
    finalizeScene(scene);  // mesh bounds and limits
    return scene;
}

}  // namespace rt
