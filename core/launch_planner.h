// rtlab — splits a frame into row tiles so that no single kernel launch runs longer than a set
// time. Display drivers kill kernels that hold a GPU too long (the report's watchdog problem);
// with tiles no launch gets near that limit. The planner learns milliseconds per row from the
// launches it has seen and sizes the next tile from them.
#pragma once

#include <algorithm>
#include <string>

namespace rt {

class LaunchPlanner {
public:
    // targetMs <= 0 disables splitting: every tile is the whole remaining frame.
    // key identifies the workload (scene, size, settings); a new key forgets what was learned.
    void begin(double targetMs, const std::string& key) {
        targetMs_ = targetMs;
        if (key != key_) {
            key_ = key;
            msPerRow_ = 0;
        }
    }

    // Rows for the next launch, at most `remaining` and never less than one.
    int nextRows(int remaining) const {
        if (targetMs_ <= 0) return remaining;
        if (msPerRow_ <= 0) return std::min(remaining, kProbeRows);  // learn first
        int rows = int(kHeadroom * targetMs_ / msPerRow_);
        return std::clamp(rows, 1, remaining);
    }

    void record(int rows, double ms) {
        if (rows > 0 && ms > 0) msPerRow_ = std::max(ms / rows, 1e-6);
    }

private:
    static constexpr int kProbeRows = 8;
    static constexpr double kHeadroom = 0.8;  // aim below the target: rows vary in cost
    double targetMs_ = 0, msPerRow_ = 0;
    std::string key_;
};

}  // namespace rt
