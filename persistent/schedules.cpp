// rtlab — the persistent megakernel's schedules (schedules.h).
#include "persistent/schedules.h"

#include <algorithm>

#include "core/cl_runtime.h"
#include "core/error.h"

namespace rt {

const std::vector<PersistSchedule>& persistSchedules() {
    using L = PersistSchedule::Loop;
    // Where each won on the H200 (persistent/README.md): flat the 4 px wall of 100% mirrors and
    // glass, nested the coherent standard scenes (16x8 strips, the megakernel's own work-groups,
    // on spheres), regrouped the walls whose neighbours shade different patterns, the bounce loop
    // the 16 px wall of 50% (2.03x) and, staged, the 4 px walls (up to 1.15x over auto).
    static const std::vector<PersistSchedule> schedules{
        {"flat", L::Flat, "4x16", false,
         "flat (one loop over rays; a lane takes a pixel when its tree ends)"},
        {"nested", L::Nested, "4x16", false,
         "nested (a loop over pixels around the megakernel's loop over rays; a work-group takes "
         "a pixel a lane once all its lanes are done)"},
        {"nested-16x8", L::Nested, "16x8", false,
         "nested-16x8 (the same in 16x8 strips, the megakernel's own work-groups)"},
        {"regrouped", L::Regrouped, "4x16", false,
         "regrouped (the flat loop; each step a work-group sorts its hits by procedural pattern "
         "in local memory, so that a warp shades one pattern at a time)"},
        {"bounce", L::Bounce, "4x16", false,
         "bounce (a wavefront inside the launch: a work-group traces a batch of twice its lanes "
         "in pixels bounce by bounce, each bounce's rays in global memory)"},
        {"bounce-staged", L::Bounce, "4x16", true,
         "bounce-staged (the same, each bounce's hits sorted by pattern and their shadow rays "
         "cast in a pass of their own)"},
    };
    return schedules;
}

const PersistSchedule& persistSchedule(const std::string& name) {
    for (const PersistSchedule& s : persistSchedules())
        if (name == s.name) return s;
    throw Error("the persistent megakernel has no schedule '" + name + "'",
                FailureKind::InvalidOption);
}

const char* PersistSchedule::file() const {
    switch (loop) {
        case Loop::Flat:
            return "flat.cl";
        case Loop::Nested:
            return "nested.cl";
        case Loop::Regrouped:
            return "regrouped.cl";
        case Loop::Bounce:
            return "bounce.cl";
    }
    return "";
}

const char* PersistSchedule::kernel() const {
    switch (loop) {
        case Loop::Flat:
        case Loop::Nested:
            return "Persistent_Render";
        case Loop::Regrouped:
            return "Persistent_RenderRegrouped";
        case Loop::Bounce:
            return "Persistent_RenderBounce";
    }
    return "";
}

size_t PersistSchedule::defaultLanes(const DeviceInfo& device) const {
    if (!device.isGpu()) return 64;
    return loop == Loop::Bounce ? std::min<size_t>(512, device.maxWorkGroup) : 128;
}

std::vector<std::string> PersistSchedule::defines(size_t lanes, const DeviceInfo& device) const {
    std::vector<std::string> d;
    // The work-group's local arrays are sized by its work-items.
    if (loop == Loop::Regrouped) d.push_back("RT_PERSIST_REGROUP=" + std::to_string(lanes));
    if (loop == Loop::Bounce) d.push_back("RT_BOUNCE_LANES=" + std::to_string(lanes));
    if (staged) d.push_back("RT_BOUNCE_STAGED");
    // The group size declared to the compiler (handout.cl, RT_GROUP_LANES), except on NVIDIA.
    if (!device.nvidia()) d.push_back("RT_REQD_GROUP_SIZE");
    const std::string order = tile;
    const size_t by = order.find('x');
    d.push_back("RT_PERSIST_TILE_W=" + order.substr(0, by));
    d.push_back("RT_PERSIST_TILE_H=" + order.substr(by + 1));
    return d;
}

}  // namespace rt
