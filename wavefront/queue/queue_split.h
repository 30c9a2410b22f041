// rtlab — --max-launch-ms for the queue wavefront's stage launches. The admission
// limit (QueuePass::adaptLimit) bounds how many new paths enter the pool, not the children of
// the paths already in it: a bounce whose rays branch (glass) runs its stages over up to C times
// the rays the last bounce had, so one such launch can run well past the cap on a slow or loaded
// device. So every stage launch whose items times the cost of one item is over the cap goes in
// pieces over sub-ranges of its queue (a global work offset), sized from what one item of that
// stage cost in the launches measured before (profiling events), as the admission limit is.
// The kernels write each result at the ray's own index, so the pieces change no pixel.
#pragma once

#include <algorithm>
#include <cstddef>
#include <map>
#include <string>

namespace rt {

class StageCosts {
  public:
    // The items of the next piece of `kernel` with `left` items to go, in whole steps (the
    // kernel's work-group size, so that pieces stay aligned to groups), at least one step.
    // targetMs <= 0: no cap, all of them.
    size_t piece(const std::string& kernel, size_t left, double targetMs, size_t step) const {
        if (targetMs <= 0 || left == 0) return left;
        step = std::max<size_t>(step, 1);
        auto it = stages_.find(kernel);
        // Never measured: a probe, which the caller times before it sizes the rest.
        double fit = it == stages_.end() ? double(kProbeItems)
                                         : kHeadroom * targetMs / (slack() * it->second);
        if (fit >= double(left)) return left;
        size_t items = std::max(size_t(fit) / step * step, step);
        return std::min(items, left);
    }
    bool known(const std::string& kernel) const { return stages_.count(kernel) != 0; }

    // `items` of `kernel` took `ms` in all (the pieces of one stage in one bounce, pooled, so
    // that a small piece's launch overhead does not stand for the cost of an item). Launches
    // that had no item teach nothing.
    //
    // How far the new cost per item strays from the last one, either way, is the slack that
    // divides the budget, as core/launch_planner.h does with rows: on a CPU device that other
    // work shares, the same stage over the same rays can take much longer from one bounce to the
    // next, and a deeper bounce's rays cost more. Only launches long enough to matter for the cap
    // (kTellingShare of it) count: a short one's time is mostly launch overhead.
    void learn(const std::string& kernel, size_t items, double ms, double targetMs) {
        if (items == 0) return;
        double perItem = std::max(ms, 1e-9) / double(items);
        auto it = stages_.find(kernel);
        if (it != stages_.end() && ms >= kTellingShare * targetMs) {
            double ratio = std::clamp(perItem / it->second, 1.0 / kMaxSlack, kMaxSlack);
            slow_ = std::max(1.0 + (slow_ - 1.0) * kSlackDecay, ratio);
            fast_ = std::min(1.0 - (1.0 - fast_) * kSlackDecay, ratio);
        }
        stages_[kernel] = perItem;
    }
    double slack() const { return std::min(slow_ / fast_, kMaxSlack); }
    void clear() { stages_.clear(); }  // a new workload; the slack is the machine's: kept

    static constexpr size_t kProbeItems = 256;  // the first launch of a stage, as kProbeRays
    static constexpr double kHeadroom = 0.8;    // aim below the cap: bounces differ in cost
    static constexpr double kTellingShare = 0.1, kMaxSlack = 4.0, kSlackDecay = 0.9;

  private:
    std::map<std::string, double> stages_;  // ms per item, by kernel
    double slow_ = 1.0, fast_ = 1.0;        // the highest and lowest recent ratio, decaying to 1
};

}  // namespace rt
