// rtlab bench — the sweep's time-left estimate (see sweep_eta.h).
#include "bench/sweep_eta.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/accel.h"
#include "pipelines/registry.h"

namespace rt::bench {

double roughCost(const Cell& c) {
    const RenderOptions& o = c.options;
    double frames = c.warmup + c.repeats + (c.countRays ? 1 : 0);
    // Rays grow about with the bounce limit; a pipeline with a global tree (one that tiles it)
    // also walks every slot of that tree.
    double work = 1.0 + o.bounces;
    if (pipelineInfo(c.pipeline).supports.tiling)
        work += double(treeNodeCount(c.branching, o.bounces)) / 16;
    return std::max(1.0, double(o.width) * o.height * o.aa * o.aa * work * frames);
}

namespace {

// The values of the options the cell's pipeline declares for itself: "|weighted".
std::string ownOptions(const Cell& c) {
    std::string out;
    for (const PipelineOption& opt : pipelineInfo(c.pipeline).options)
        out += "|" + opt.text(opt.value(c.options.pipelineOptions));
    return out;
}

}  // namespace

std::string SweepEta::programKey(const Cell& c) {
    const RenderOptions& o = c.options;
    return c.scene + "|" + c.pipeline + "|b" + std::to_string(o.bounces) + "|" +
           (c.accelApplies ? accelName(o.accel) : "-") + ownOptions(c) + "|" +
           offsetName(o.offset) + (o.robustSphere ? "|robust" : "") +
           (o.watertight ? "|watertight" : "") + (c.countRays ? "|counted" : "");
}

SweepEta::Levels SweepEta::levels(const Cell& c) {
    const RenderOptions& o = c.options;
    // Most telling first: with few cells measured the fit puts a difference on the pipeline
    // before the scene, and on the scene before the size.
    return {c.pipeline + ownOptions(c),
            c.scene,
            std::to_string(double(o.width) * o.height * o.aa * o.aa),
            std::to_string(o.bounces),
            std::to_string(o.shadowSamples),
            c.accelApplies ? accelName(o.accel) : "-"};
}

void SweepEta::started(const Cell& c) { builder_.emplace(programKey(c), c.key()); }

void SweepEta::measured(const Cell& c, double seconds, double buildSeconds, bool ran) {
    started(c);  // a no-op unless the caller skipped it
    buildSeconds = std::clamp(buildSeconds, 0.0, std::max(0.0, seconds));
    if (builder_.at(programKey(c)) == c.key())
        for (const std::string& key : {c.pipeline, std::string()}) {
            auto& b = builds_[key];
            b.first += buildSeconds;
            ++b.second;
        }
    if (!ran) return;
    // A frame time of zero (a clock's resolution) must not become log(0).
    double frames = std::max(seconds - buildSeconds, 1e-6);
    samples_.push_back({levels(c), std::log(frames / roughCost(c))});
    fit();
}

// Backfitting: each factor in turn takes the mean residual of its levels given the others, until
// nothing moves; that is the least-squares fit of the log ratio as a sum of factors. Each
// factor's levels are kept centred (weighted by cells), so that an unseen level, at 0, is the
// average one.
void SweepEta::fit() {
    const size_t n = samples_.size();
    mean_ = 0;
    for (const Sample& s : samples_) mean_ += s.logRatio / double(n);
    for (auto& e : effects_) e.clear();
    for (int iteration = 0; iteration < 200; ++iteration) {
        double moved = 0;
        for (int f = 0; f < kFactors; ++f) {
            std::map<std::string, std::pair<double, int>> sums;
            for (const Sample& s : samples_) {
                double rest = mean_;
                for (int g = 0; g < kFactors; ++g)
                    if (g != f) rest += effects_[size_t(g)][s.levels[size_t(g)]];
                auto& sum = sums[s.levels[size_t(f)]];
                sum.first += s.logRatio - rest;
                ++sum.second;
            }
            double centre = 0;
            for (const auto& [level, sum] : sums) centre += sum.first / double(n);
            auto& effect = effects_[size_t(f)];
            for (const auto& [level, sum] : sums) {
                double value = sum.first / sum.second - centre;
                moved = std::max(moved, std::abs(value - effect[level]));
                effect[level] = value;
            }
            mean_ += centre;
        }
        if (moved < 1e-12) break;
    }
}

double SweepEta::frameSeconds(const Cell& c) const {
    if (samples_.empty()) return 0;
    double log = mean_;
    Levels l = levels(c);
    for (int f = 0; f < kFactors; ++f)
        if (auto it = effects_[size_t(f)].find(l[size_t(f)]); it != effects_[size_t(f)].end())
            log += it->second;
    return std::exp(log) * roughCost(c);
}

double SweepEta::buildSeconds(const Cell& c) const {
    if (auto it = builder_.find(programKey(c)); it != builder_.end() && it->second != c.key())
        return 0;
    for (const std::string& key : {c.pipeline, std::string()})
        if (auto it = builds_.find(key); it != builds_.end())
            return it->second.first / it->second.second;
    return 0;
}

double SweepEta::remaining(const std::vector<const Cell*>& cells) const {
    double seconds = 0;
    std::set<std::string> charged;
    for (const Cell* c : cells) {
        seconds += frameSeconds(*c);
        if (charged.insert(programKey(*c)).second) seconds += buildSeconds(*c);
    }
    return seconds;
}

}  // namespace rt::bench
