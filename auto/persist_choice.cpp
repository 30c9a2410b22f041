// rtlab — the persistent megakernel's schedule chosen from a scene's predicted warps
// (persist_choice.h).
#include "auto/persist_choice.h"

#include <cstdio>

namespace rt {

PersistChoice choosePersistentSchedule(const LaneEstimate& e) {
    char lanes[80], objects[80];
    std::snprintf(lanes, sizeof lanes, "%.1f busy lanes of %d predicted", e.busyLanes, e.lanes);
    std::snprintf(objects, sizeof objects, "%.1f objects a warp", e.objectsPerWarp);
    if (e.busyLanes < kRegroupBelowLanes) {
        char why[64];
        std::snprintf(why, sizeof why, " (below %.1f)", kRegroupBelowLanes);
        return {true, std::string(lanes) + why +
                          ": trees disagree, so work-groups regroup their hits by pattern"};
    }
    if (e.objectsPerWarp >= kRegroupFromObjects) {
        char why[64];
        std::snprintf(why, sizeof why, " (at least %.1f)", kRegroupFromObjects);
        return {true, std::string(objects) + why +
                          ": a warp shades several patterns, so work-groups regroup their "
                          "hits by pattern"};
    }
    return {false, std::string(lanes) + " and " + objects +
                       ": trees and patterns agree, so the nested loop keeps a work-group on "
                       "neighbours"};
}

}  // namespace rt
