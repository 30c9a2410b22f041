// rtlab — splits a frame into tiles so that no single kernel launch runs longer than a set
// time. Display drivers kill kernels that hold a GPU too long (the report's watchdog problem);
// with tiles no launch gets near that limit. The planner learns what each row costs from the
// launches it has seen and sizes the next tile from that.
//
// Rows differ a lot in cost (sky against glass at a high bounce limit: 100x and more), so one
// average cost per row is not enough: a frame whose cheap rows come first would end in one long
// launch over its costly ones. The planner therefore keeps the cost of every row of the frame
// (a profile, kept while the workload stays the same) and fills each tile from it. These rules
// keep a launch under the target once rows were measured:
//  - a launch measures only the sum over its rows, so the rows of one launch (a segment) are
//    taken whole or, when the segment alone is over the target, cut; a part is priced at
//    kCutMargin times its rows' even share (never above the whole), because a segment's cost
//    need not be spread evenly (a few rows of glass among sky can hold most of it, and an even
//    share then prices a part that holds them far too low);
//  - a row costlier than the target alone is split into column tiles (when the caller can
//    launch part of a row; the megakernel can, the tree wavefront keeps whole rows); the pieces
//    of such a row are kept as its column profile, and the next frame cuts the row from them, as
//    rows are cut from segments (a row's cost may sit in some of its columns: priced evenly,
//    a piece over them is predicted too cheap, and overruns, every frame);
//  - the budget shrinks by how far recent launches strayed from their predictions, either way
//    (timing noise of a shared machine), and relaxes again as launches keep to them;
//  - rows not seen yet are priced at the costliest row seen so far, and a tile over them grows
//    at most twofold in pixels from one launch to the next, starting from a probe of one row
//    (or part of one) so that even the first launch stays short.
#pragma once

#include <algorithm>
#include <map>
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
            columns_.clear();
            maxRowMs_ = 0;
        }
        width_ = width;
        colStep_ = std::max(colStep, 1);
        pos_ = 0;
        col_ = 0;
        partialMs_ = 0;
        pieces_.clear();
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
        if (width_ > 0 && lastPixels_ > 0)
            rows = std::min(rows, int(pixelCap / width_));
        else if (lastPixels_ > 0)
            rows = std::min(rows, int(pixelCap));  // row units
        if (rows >= 1) return {std::min(rows, remaining), 0, 0};
        return width_ > 0 ? columns(budget) : LaunchTile{1, 0, 0};
    }

    // Whole rows only (for callers that cannot launch part of a row).
    int nextRows(int remaining) const { return std::max(next(remaining).rows, 1); }

    // What the planner predicts a tile costs from what it has measured (tests check that no
    // planned tile is predicted over the target once its rows were measured).
    // A cut of a measured segment or row is priced with the cut margin (margin = false: at its
    // even share, what the slack compares launches with).
    double predictedMs(const LaunchTile& t, bool margin = true) const {
        return t.partialRow() ? columnsMs(t.col0, t.cols, margin) : rowsMs(t.rows, margin);
    }

    // The launch just made (the tile next() returned) took `ms`.
    void record(const LaunchTile& t, double ms) {
        ms = std::max(ms, 1e-6);
        learnSlack(t, ms);
        if (t.partialRow()) {
            partialMs_ += ms;
            pieces_.push_back({t.col0, t.cols, ms});
            maxRowMs_ = std::max(maxRowMs_, ms * double(width_) / double(t.cols));
            lastPixels_ = t.cols;
            col_ = t.col0 + t.cols;
            if (col_ < width_) return;
            size_t row = pos_;
            store(1, partialMs_);  // the row is complete: its cost is the sum of its pieces
            columns_[row] = pieces_;
            pieces_.clear();
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
    // Rows measured before: whole segments while they fit; a part of the first segment (priced
    // as a cut) when even that one does not; columns of one row when no part does.
    LaunchTile measuredRows(int remaining, double budget) const {
        double whole = 0, part = 0, segment = 0;  // segments taken whole; the current one
        int rows = 0, wholeRows = 0, cutRows = 0;
        for (size_t r = pos_; rows < remaining && r < profile_.size(); ++r) {
            if (part == 0) segment = segmentMs(r);
            part += profile_[r];
            if (whole + part > budget) break;  // even at its even share no more fits
            ++rows;
            bool segmentEnds = r + 1 >= profile_.size() || segment_[r + 1] != segment_[r];
            if (segmentEnds || rows == remaining) {
                whole += part;
                part = 0;
                wholeRows = rows;
            } else if (wholeRows == 0 && cutMs(part, segment, true) <= budget) {
                cutRows = rows;
            }
        }
        if (wholeRows > 0) return {wholeRows, 0, 0};
        if (cutRows > 0) return {cutRows, 0, 0};
        return width_ > 0 ? columns(budget) : LaunchTile{1, 0, 0};
    }

    // What rows [pos_, pos_ + rows) cost: segments wholly inside at what they measured, a
    // segment cut by the tile's end as a cut (cutMs), rows not seen yet at the costliest row seen.
    double rowsMs(int rows, bool margin) const {
        const size_t end = pos_ + size_t(rows);
        double sum = 0, part = 0, segment = 0;
        for (size_t r = pos_; r < end; ++r) {
            if (r >= profile_.size()) {
                sum += maxRowMs_;
                continue;
            }
            if (part == 0) segment = segmentMs(r);
            part += profile_[r];
            bool segmentEnds = r + 1 >= profile_.size() || segment_[r + 1] != segment_[r];
            if (segmentEnds) sum += part, part = 0;
        }
        return sum + (part > 0 ? cutMs(part, segment, margin) : 0.0);
    }

    // Columns of the current row: as many column steps as fit the budget (columnsMs).
    LaunchTile columns(double budget) const {
        const int left = width_ - col_;
        int cols = std::min(colStep_, left);
        while (cols < left && columnsMs(col_, std::min(cols + colStep_, left), true) <= budget)
            cols = std::min(cols + colStep_, left);
        if (pos_ >= profile_.size() && lastPixels_ > 0)
            cols = std::min(cols, std::max(roundCols(2 * lastPixels_), colStep_));
        return {1, col_, cols};
    }

    // What columns [col0, col0 + cols) of the current row cost. From the row's column profile
    // (its pieces last frame) when it has one: pieces wholly inside at what they measured, a
    // piece cut as a cut (cutMs). Otherwise a cut of the row's share of its segment; a row not
    // seen yet is priced at the costliest row seen, a bound already.
    double columnsMs(int col0, int cols, bool margin) const {
        if (pos_ >= profile_.size()) return maxRowMs_ * cols / width_;
        auto it = columns_.find(pos_);
        if (it == columns_.end())
            return cutMs(profile_[pos_] * cols / width_, segmentMs(pos_), margin);
        double sum = 0;
        for (const Piece& p : it->second) {
            int overlap = std::min(col0 + cols, p.col0 + p.cols) - std::max(col0, p.col0);
            if (overlap <= 0) continue;
            sum += overlap == p.cols ? p.ms : cutMs(p.ms * overlap / p.cols, p.ms, margin);
        }
        return sum;
    }

    // A part of something measured as a whole (a segment, a row, a piece) that cost `whole`,
    // whose even share is `share`: the whole's cost may sit in the part, so it is priced at
    // kCutMargin times its share, never above the whole (no part costs more).
    double cutMs(double share, double whole, bool margin) const {
        if (!margin) return share;
        return std::min(kCutMargin * share, whole);
    }

    // What the rows from `row` to the end of its segment cost.
    double segmentMs(size_t row) const {
        double sum = 0;
        for (size_t r = row; r < profile_.size() && segment_[r] == segment_[row]; ++r)
            sum += profile_[r];
        return sum;
    }

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

    // How far launches over measured rows stray from their predictions: on a shared machine
    // the same rows can take far longer from one frame to the next (a CPU device whose cores
    // other work also loads). The profile keeps what rows cost the last time, slow or not, so a
    // slow launch is seen as one over its prediction or, once its rows were measured slow, as
    // a fast launch under it: the slack is the spread between the highest and the lowest
    // recent ratio of actual to predicted. The budget is divided by it; both ends decay back
    // towards 1 launch by launch.
    void learnSlack(const LaunchTile& t, double ms) {
        bool measured = t.partialRow() ? pos_ < profile_.size()
                                       : pos_ + size_t(std::max(t.rows, 0)) <= profile_.size();
        // Against the even share: the cut margin is a guard, not a prediction of the noise.
        double predicted = measured ? predictedMs(t, false) : 0;
        double ratio = predicted > 0 ? std::clamp(ms / predicted, 1.0 / kMaxSlack, kMaxSlack) : 1.0;
        slow_ = std::max(1.0 + (slow_ - 1.0) * kSlackDecay, ratio);
        fast_ = std::min(1.0 - (1.0 - fast_) * kSlackDecay, ratio);
        slack_ = std::min(slow_ / fast_, kMaxSlack);
    }

    int roundCols(int cols) const { return std::max(cols / colStep_ * colStep_, colStep_); }

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
            columns_.erase(r);  // launched whole: its column profile is stale
        }
        pos_ = end;
    }

    static constexpr int kProbePixels = 256;  // the first launch of a workload: one row at most
    static constexpr double kHeadroom = 0.8;  // aim below the target: timings vary
    // A part of a measured segment (or row, or piece) is priced at this many times its even
    // share: a cut then errs past the headroom only where a part holds over twice its share.
    // Each frame's launches refine the profile, so such an error shrinks frame by frame.
    static constexpr double kCutMargin = 2.0;
    static constexpr double kMaxSlack = 4.0, kSlackDecay = 0.9;
    double targetMs_ = 0, maxRowMs_ = 0, partialMs_ = 0;
    // Kept across workloads: they are the machine's, not the scene's.
    double slack_ = 1.0, slow_ = 1.0, fast_ = 1.0;
    std::string key_;
    int width_ = 0, colStep_ = 1;
    std::vector<double> profile_;    // ms per row, by row of the frame (passes one after another)
    std::vector<unsigned> segment_;  // which launch measured each row
    // Rows launched in column pieces: the pieces (columns and what they took), by row.
    struct Piece {
        int col0, cols;
        double ms;
    };
    std::map<size_t, std::vector<Piece>> columns_;
    std::vector<Piece> pieces_;  // of the row being launched in pieces
    unsigned segmentId_ = 0;
    size_t pos_ = 0;      // the frame's next row
    int col_ = 0;         // the next column of a row launched in pieces (0: at a row start)
    int lastPixels_ = 0;  // pixels of the last launch (rows when planning whole rows only)
};

}  // namespace rt
