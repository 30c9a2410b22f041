// rtlab — splits a frame into row tiles so that no single kernel launch runs longer than a set
// time. Display drivers kill kernels that hold a GPU too long (the report's watchdog problem);
// with tiles no launch gets near that limit. The planner learns what each row costs from the
// launches it has seen and sizes the next tile from that.
//
// Rows differ a lot in cost (sky against glass at a high bounce limit: 100x and more), so one
// average cost per row is not enough: a frame whose cheap rows come first would end in one long
// launch over its costly ones. The planner therefore keeps the cost of every row of the frame
// (a profile, kept while the workload stays the same) and fills each tile from it; rows it has
// not seen yet are met with tiles that grow at most twofold from one launch to the next.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

namespace rt {

class LaunchPlanner {
public:
    // targetMs <= 0 disables splitting: every tile is the whole remaining frame.
    // key identifies the workload (scene, size, settings); a new key forgets what was learned.
    // Called once per frame: the tiles of a frame are then planned and recorded in order.
    void begin(double targetMs, const std::string& key) {
        targetMs_ = targetMs;
        if (key != key_) {
            key_ = key;
            msPerRow_ = 0;
            profile_.clear();
        }
        pos_ = 0;
        lastRows_ = 0;
    }

    // Rows for the next launch, at most `remaining` and never less than one.
    int nextRows(int remaining) const {
        if (targetMs_ <= 0) return remaining;
        const double budget = kHeadroom * targetMs_;
        if (pos_ < profile_.size()) {
            // Rows measured before: as many as their costs fit in the budget.
            double sum = 0;
            int rows = 0;
            while (rows < remaining && pos_ + size_t(rows) < profile_.size() &&
                   sum + profile_[pos_ + size_t(rows)] <= budget)
                sum += profile_[pos_ + size_t(rows++)];
            return std::clamp(rows, 1, remaining);
        }
        if (msPerRow_ <= 0) return std::min(remaining, kProbeRows);  // learn first
        int rows = int(budget / msPerRow_);
        if (lastRows_ > 0) rows = std::min(rows, 2 * lastRows_);  // unseen rows: grow slowly
        return std::clamp(rows, 1, remaining);
    }

    // The launch just made covered `rows` rows (the next ones of the frame) and took `ms`.
    void record(int rows, double ms) {
        if (rows <= 0) return;
        if (ms > 0) msPerRow_ = std::max(ms / rows, 1e-6);
        double perRow = std::max(ms / rows, 1e-6);
        if (profile_.size() < pos_ + size_t(rows)) profile_.resize(pos_ + size_t(rows), 0.0);
        std::fill(profile_.begin() + long(pos_), profile_.begin() + long(pos_ + size_t(rows)), perRow);
        pos_ += size_t(rows);
        lastRows_ = rows;
    }

private:
    static constexpr int kProbeRows = 8;
    static constexpr double kHeadroom = 0.8;  // aim below the target: rows vary in cost
    double targetMs_ = 0, msPerRow_ = 0;
    std::string key_;
    std::vector<double> profile_;  // ms per row, by row of the frame (passes one after another)
    size_t pos_ = 0;               // the frame's next row
    int lastRows_ = 0;
};

}  // namespace rt
