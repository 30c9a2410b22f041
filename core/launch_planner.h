// rtlab — splits a frame into tiles so that no single kernel launch runs longer than a set
// time. Display drivers kill kernels that hold a GPU too long (the report's watchdog problem);
// with tiles no launch gets near that limit. The planner learns what each row costs from the
// launches it has seen and sizes the next tile from that.
//
// Rows differ a lot in cost (sky against glass at a high bounce limit: 100x and more), so one
// average cost per row is not enough: a frame whose cheap rows come first would end in one long
// launch over its costly ones. The planner therefore keeps the cost of every row of the frame
// (a profile, kept while the workload stays the same) and fills each tile from it. Three rules
// keep a launch under the target once rows were measured:
//  - a launch measures only the sum over its rows, so the rows of one launch (a segment) are
//    taken whole or, when the segment alone is over the target, in the fraction that fits:
//    cutting a measured segment at an arbitrary row would assume its cost is spread evenly;
//  - a row costlier than the target alone is split into column tiles (when the caller can
//    launch part of a row; the megakernel can, the tree wavefront keeps whole rows);
//  - the budget shrinks by how much longer than predicted recent launches ran (timing noise
//    of a shared machine), and relaxes again as launches keep to their predictions;
//  - rows not seen yet are priced at the costliest row seen so far, and a tile over them grows
//    at most twofold in pixels from one launch to the next, starting from a probe of one row
//    (or part of one) so that even the first launch stays short.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

namespace rt {

// One launch: `rows` whole rows, or (cols > 0) columns [col0, col0 + cols) of one row.
struct LaunchTile {
    int rows = 0;
    int col0 = 0, cols = 0;
    bool partialRow() const { return cols > 0; }
};

class LaunchPlanner {
public:
    // targetMs <= 0 disables splitting: every tile is the whole remaining frame.
    // key identifies the workload (scene, size, settings); a new key forgets what was learned.
    // width > 0 lets a tile be part of one row, in steps of colStep columns (the work-group
    // width, so that no work-item is wasted); width 0 plans whole rows only.
    // Called once per frame: the tiles of a frame are then planned and recorded in order.
    void begin(double targetMs, const std::string& key, int width = 0, int colStep = 1) {
        targetMs_ = targetMs;
        if (key != key_ || width != width_) {
            key_ = key;
            profile_.clear();
            segment_.clear();
            maxRowMs_ = 0;
        }
        width_ = width;
        colStep_ = std::max(colStep, 1);
        pos_ = 0;
        col_ = 0;
        partialMs_ = 0;
        lastPixels_ = 0;
    }

    // The next launch: at most `remaining` rows (counted from the current row), at least one
    // row or, for a partial row, at least one column step.
    LaunchTile next(int remaining) const {
        if (targetMs_ <= 0 || remaining <= 0) return {std::max(remaining, 0), 0, 0};
        const double budget = kHeadroom * targetMs_ / slack_;
        if (col_ > 0) return columns(budget);  // finish the row begun
        if (pos_ < profile_.size()) return measuredRows(remaining, budget);
        if (maxRowMs_ <= 0) {  // nothing measured yet: a probe of one row, or part of one
            if (width_ > kProbePixels) return {1, 0, roundCols(kProbePixels)};
            return {1, 0, 0};
        }
        // Unseen rows, priced at the costliest row seen; grow at most twofold in pixels.
        double pixelCap = 2.0 * lastPixels_;
        int rows = int(budget / maxRowMs_);
        if (width_ > 0 && lastPixels_ > 0) rows = std::min(rows, int(pixelCap / width_));
        else if (lastPixels_ > 0) rows = std::min(rows, int(pixelCap));  // row units
        if (rows >= 1) return {std::min(rows, remaining), 0, 0};
        return width_ > 0 ? columns(budget) : LaunchTile{1, 0, 0};
    }

    // Whole rows only (for callers that cannot launch part of a row).
    int nextRows(int remaining) const { return std::max(next(remaining).rows, 1); }

    // What the planner predicts a tile costs from what it has measured (tests check that no
    // planned tile is predicted over the target once its rows were measured).
    double predictedMs(const LaunchTile& t) const {
        if (t.partialRow()) return columnMs() * t.cols;
        double sum = 0;
        for (int r = 0; r < t.rows; ++r) sum += rowCost(pos_ + size_t(r));
        return sum;
    }

    // The launch just made (the tile next() returned) took `ms`.
    void record(const LaunchTile& t, double ms) {
        ms = std::max(ms, 1e-6);
        learnSlack(t, ms);
        if (t.partialRow()) {
            partialMs_ += ms;
            maxRowMs_ = std::max(maxRowMs_, ms * double(width_) / double(t.cols));
            lastPixels_ = t.cols;
            col_ = t.col0 + t.cols;
            if (col_ < width_) return;
            store(1, partialMs_);  // the row is complete: its cost is the sum of its pieces
            col_ = 0;
            partialMs_ = 0;
            return;
        }
        if (t.rows <= 0) return;
        maxRowMs_ = std::max(maxRowMs_, ms / t.rows);
        lastPixels_ = width_ > 0 ? t.rows * width_ : t.rows;
        store(t.rows, ms);
    }
    void record(int rows, double ms) { record(LaunchTile{rows, 0, 0}, ms); }

private:
    // Rows measured before: whole segments while they fit; the fraction of a segment that fits
    // when even its first part does not; columns of one row when that row alone does not.
    LaunchTile measuredRows(int remaining, double budget) const {
        double sum = 0;
        int rows = 0, whole = 0;
        for (size_t r = pos_; rows < remaining && r < profile_.size(); ++r) {
            if (sum + profile_[r] > budget) break;
            sum += profile_[r];
            ++rows;
            bool segmentEnds = r + 1 >= profile_.size() || segment_[r + 1] != segment_[r];
            if (segmentEnds || rows == remaining) whole = rows;
        }
        if (whole > 0) return {whole, 0, 0};
        if (rows > 0) return {rows, 0, 0};  // a part of a segment that alone exceeds the budget
        if (width_ > 0) return columns(budget);
        return {1, 0, 0};
    }

    // Columns of the current row: as many as its cost per column fits in the budget.
    LaunchTile columns(double budget) const {
        int left = width_ - col_;
        double perCol = columnMs();
        int cols = perCol > 0 ? int(budget / perCol) : left;
        if (pos_ >= profile_.size() && lastPixels_ > 0) cols = std::min(cols, 2 * lastPixels_);
        cols = std::min(roundCols(cols), left);
        return {1, col_, cols};
    }

    // What one column of the current row costs: a row's cost is taken as even across it.
    double columnMs() const { return rowCost(pos_) / width_; }

    // A launch over the first part of a measured segment that goes on after it: the rest of
    // the segment costs what the segment cost less this part. Only raised, never lowered: a
    // part that took longer than its share says nothing certain about the rest.
    void refineRest(size_t end, double ms) {
        if (end >= profile_.size() || segment_[pos_] != segment_[end]) return;
        double covered = 0, rest = 0;
        for (size_t r = pos_; r < end; ++r) covered += profile_[r];
        size_t restEnd = end;
        while (restEnd < profile_.size() && segment_[restEnd] == segment_[end])
            rest += profile_[restEnd++];
        double scale = rest > 0 ? std::max(covered + rest - ms, rest) / rest : 1.0;
        for (size_t r = end; r < restEnd; ++r) profile_[r] *= scale;
    }

    // How much longer than predicted launches over measured rows run: on a shared machine the
    // same rows take 1.5x and more from one frame to the next (the PoCL limits sweep at a load
    // of 9 on 2 cores). The budget is divided by it; it decays back towards 1 launch by launch.
    void learnSlack(const LaunchTile& t, double ms) {
        bool measured = t.partialRow() ? pos_ < profile_.size()
                                       : pos_ + size_t(std::max(t.rows, 0)) <= profile_.size();
        double predicted = measured ? predictedMs(t) : 0;
        double decayed = 1.0 + (slack_ - 1.0) * kSlackDecay;
        double ratio = predicted > 0 ? std::min(ms / predicted, kMaxSlack) : 1.0;
        slack_ = std::max(decayed, ratio);
    }

    int roundCols(int cols) const { return std::max(cols / colStep_ * colStep_, colStep_); }

    double rowCost(size_t row) const { return row < profile_.size() ? profile_[row] : maxRowMs_; }

    void store(int rows, double ms) {
        size_t end = pos_ + size_t(rows);
        refineRest(end, ms);
        if (profile_.size() < end) {
            profile_.resize(end, 0.0);
            segment_.resize(end, 0);
        }
        ++segmentId_;
        for (size_t r = pos_; r < end; ++r) {
            profile_[r] = ms / rows;
            segment_[r] = segmentId_;
        }
        pos_ = end;
    }

    static constexpr int kProbePixels = 256;  // the first launch of a workload: one row at most
    static constexpr double kHeadroom = 0.8;  // aim below the target: timings vary
    static constexpr double kMaxSlack = 4.0, kSlackDecay = 0.9;
    double targetMs_ = 0, maxRowMs_ = 0, partialMs_ = 0;
    double slack_ = 1.0;  // kept across workloads: it is the machine's, not the scene's
    std::string key_;
    int width_ = 0, colStep_ = 1;
    std::vector<double> profile_;  // ms per row, by row of the frame (passes one after another)
    std::vector<unsigned> segment_;  // which launch measured each row
    unsigned segmentId_ = 0;
    size_t pos_ = 0;  // the frame's next row
    int col_ = 0;     // the next column of a row launched in pieces (0: at a row start)
    int lastPixels_ = 0;  // pixels of the last launch (rows when planning whole rows only)
};

}  // namespace rt
