#include "core/accel.h"

#include "core/error.h"

namespace rt {

const char* accelName(RenderOptions::Accel accel) {
    switch (accel) {
        case RenderOptions::Accel::None: return "none";
        case RenderOptions::Accel::Bv: return "bv";
        case RenderOptions::Accel::Grid: return "grid";
        case RenderOptions::Accel::Bvh: return "bvh";
    }
    return "?";
}

RenderOptions::Accel parseAccel(const std::string& name) {
    if (name == "none") return RenderOptions::Accel::None;
    if (name == "bv") return RenderOptions::Accel::Bv;
    if (name == "grid") return RenderOptions::Accel::Grid;
    if (name == "bvh") return RenderOptions::Accel::Bvh;
    throw Error("--accel " + name + ": must be one of none, bv, grid, bvh");
}

AccelData buildAccel(const Scene& scene, RenderOptions::Accel accel) {
    AccelData out;
    out.triangles = scene.triangles;
    out.meshes = scene.meshes;
    if (accel == RenderOptions::Accel::Grid || accel == RenderOptions::Accel::Bvh)
        throw Error(std::string("--accel ") + accelName(accel) + ": not implemented yet");
    return out;
}

}  // namespace rt
