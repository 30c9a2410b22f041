// rtlab bench — the time a sweep has left, learnt from the cells it measured. Both front ends of
// the sweep loop (bench/sweep_runner.cpp) and rtlab-bench's Google Benchmark mode print it.
//
// A cell's time is a program build, paid by the first cell of each program, plus its frames.
// The frames cost the cell's rough relative cost (roughCost: pixels, bounces, frames) times one
// factor per kind of cell: pipeline and the settings of its own options (the megakernel's layout),
// scene, pixel count, bounce limit, shadow samples and accel. The factors are a least-squares fit
// of the measured cells' log(seconds / rough cost), so the queue wavefront measured on one scene
// prices it on the next; a factor value no measured cell had is the average one (the rough cost
// stands in for it).
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "bench/sweep_config.h"

namespace rt::bench {

// A rough relative cost of a cell from its settings alone: pixels, samples, the rays of its
// bounce limit, the slots of a global ray tree, and its frames.
double roughCost(const Cell& c);

class SweepEta {
  public:
    // What a cell's build is keyed by: cells of one program key build once (the context keeps
    // the programs); settings outside it (size, samples, frames) never change a program.
    static std::string programKey(const Cell& c);

    // A cell started: the later cells of its program are not charged the build again.
    void started(const Cell& c);
    // A cell measured: `seconds` in all, `buildSeconds` of them in program builds and loads.
    // Only cells that ran are fitted (a failed cell's time is not its frames'); the build of the
    // first cell of a program counts, ran or not.
    void measured(const Cell& c, double seconds, double buildSeconds, bool ran = true);

    // Seconds the cell's frames should take.
    double frameSeconds(const Cell& c) const;
    // Seconds its program build should take: 0 when a cell of the program started already, else
    // what builds of the same pipeline took, else builds of any pipeline, else 0.
    double buildSeconds(const Cell& c) const;
    double estimate(const Cell& c) const { return frameSeconds(c) + buildSeconds(c); }
    // The cells in the order they will run; each program's build is charged to its first.
    double remaining(const std::vector<const Cell*>& cells) const;

    int cellsMeasured() const { return int(samples_.size()); }

  private:
    static constexpr int kFactors = 6;
    using Levels = std::array<std::string, kFactors>;
    static Levels levels(const Cell& c);
    void fit();

    struct Sample {
        Levels levels;
        double logRatio;  // log(frame seconds / rough cost)
    };
    std::vector<Sample> samples_;
    double mean_ = 0;  // the average log ratio, which every factor is relative to
    std::array<std::map<std::string, double>, kFactors> effects_;  // log factor per level
    std::map<std::string, std::string> builder_;  // program key -> key of its first cell
    // Seconds and count of the builds measured, per pipeline and ("" key) overall.
    std::map<std::string, std::pair<double, int>> builds_;
};

}  // namespace rt::bench
