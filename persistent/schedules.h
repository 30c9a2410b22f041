// rtlab — the schedules of the persistent megakernel, each a unit: one kernel in a file of its
// own over the shared hand-out code (persistent/handout.cl), registered here with what the host
// needs to build and launch it. `--persistent-schedule` picks one; `auto` picks per scene
// (persistent_auto.cpp). Only schedules that won or tied somewhere measured are kept; what the
// deleted ones found is in persistent/README.md ("What was tried and what it found").
#pragma once

#include <string>
#include <vector>

namespace rt {

struct DeviceInfo;

struct PersistSchedule {
    enum class Loop {
        Flat,       // flat.cl: one loop over rays, a lane takes a pixel when its tree ends
        Nested,     // nested.cl: a loop over pixels around the megakernel's loop over rays
        Regrouped,  // regrouped.cl: the flat loop, each step's hits sorted by pattern
        Bounce,     // wavefront/bounce/bounce.cl: a work-group's batch traced bounce by bounce
    };
    const char* name;  // --persistent-schedule's choice
    Loop loop;         // which kernel
    const char* tile;  // the strips pixels are handed out in (Persistent_PixelOf)
    bool staged;       // Bounce: each bounce's hits sorted by pattern, shadow rays in a pass
    const char* help;  // one phrase for --help

    const char* file() const;    // its OpenCL source
    const char* kernel() const;  // its kernel's name
    // Work-items a work-group where --persistent-lanes is not given: 128 on a GPU (512 in the
    // bounce loop, whose warps meet only between bounces: a bigger group gives each warp more
    // rays between meetings), 64 elsewhere. The host lowers it to what the kernel as built runs.
    size_t defaultLanes(const DeviceInfo& device) const;
    // Whether a work-item keeps the weighted megakernel's stack of pending rays.
    bool keepsStack() const { return loop != Loop::Bounce; }
    // The program's defines for work-groups of `lanes` (the scene's and the megakernel's come
    // first, from the caller).
    std::vector<std::string> defines(size_t lanes, const DeviceInfo& device) const;
};

// Every schedule, the default (flat) first.
const std::vector<PersistSchedule>& persistSchedules();
// The schedule of that --persistent-schedule name; throws rt::Error for another.
const PersistSchedule& persistSchedule(const std::string& name);

// Bytes of local memory a regrouped lane keeps: regrouped.cl's RegroupSlot, a union of a hit
// (Node, 48, and Pending, 64 with its float3 alignment) and a shading result (a float3 term, two
// Pendings and a child mask, 148, padded to 160).
inline constexpr size_t kRegroupSlotBytes = 160;

}  // namespace rt
