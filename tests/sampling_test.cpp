// The soft-shadow sampler (core/sampling.h): stratified, jittered per shading point,
// and free of the bias a fixed pattern has, which a penumbra showed as concentric bands.
#include "core/sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <set>

namespace rt {
namespace {

// Every ring of equal area holds exactly one of the n samples, for any key.
TEST(ShadowSampler, EveryRingHoldsExactlyOneSample) {
    for (int n : {1, 2, 5, 16, 64, 255})
        for (uint32_t key : {0u, 1u, dev::Sampling_PointKey(17, 3, 2, 1), 0xffffffffu}) {
            std::vector<int> perRing(size_t(n), 0);
            for (int k = 0; k < n; ++k) {
                DiskSample s = shadowDiskSample(key, 1, k, n);
                ASSERT_GE(s.radius, 0.0);
                ASSERT_LT(s.radius, 1.0);
                int ring = int(s.radius * s.radius * n);
                ASSERT_GE(ring, 0);
                ASSERT_LT(ring, n);
                ++perRing[size_t(ring)];
            }
            for (int c : perRing) EXPECT_EQ(c, 1) << "n " << n << " key " << key;
        }
}

// Neighbouring pixels, AA samples, depths and lights get different samples: a shared pattern is
// what lined the bands of neighbouring pixels up.
TEST(ShadowSampler, SamplesDifferBetweenNeighbours) {
    auto first = [](uint32_t key, int light) {
        DiskSample s = shadowDiskSample(key, light, 3, 16);
        return std::make_pair(s.radius, std::fmod(s.angle, 6.283185307179586));
    };
    std::set<std::pair<double, double>> seen;
    int keys = 0;
    for (int y = 10; y < 14; ++y)
        for (int x = 20; x < 24; ++x)
            for (int sample = 0; sample < 2; ++sample)
                for (int depth = 0; depth < 2; ++depth)
                    for (int light = 0; light < 2; ++light) {
                        seen.insert(first(dev::Sampling_PointKey(x, y, sample, depth), light));
                        ++keys;
                    }
    EXPECT_EQ(int(seen.size()), keys);
    // The same key always gives the same sample: pipelines and the reference agree.
    EXPECT_EQ(first(dev::Sampling_PointKey(5, 6, 0, 2), 1),
              first(dev::Sampling_PointKey(5, 6, 0, 2), 1));
}

// A straight shadow edge across the light's disk at distance d from its centre hides the
// fraction (acos d - d sqrt(1 - d^2)) / pi of the disk. The fraction of the n = 16 samples
// beyond the edge, averaged over many pixels, must follow it: what a fixed pattern gets wrong
// is the same in every pixel (a bias, seen as bands along the penumbra), what the jittered one
// gets wrong differs from pixel to pixel and averages out.
double worstBias(const std::function<DiskSample(uint32_t, int)>& sample, int pixels) {
    const int n = 16;
    double worst = 0;
    for (double edgeAngle : {0.0, 0.7, 2.0})
        for (int i = -19; i <= 19; ++i) {
            double d = i / 20.0;
            double truth = (std::acos(d) - d * std::sqrt(1 - d * d)) / M_PI;
            double sum = 0;
            for (int p = 0; p < pixels; ++p) {
                uint32_t key = dev::Sampling_PointKey(p % 64, p / 64, 0, 0);
                int beyond = 0;
                for (int k = 0; k < n; ++k) {
                    DiskSample s = sample(key, k);
                    if (s.radius * std::cos(s.angle - edgeAngle) > d) ++beyond;
                }
                sum += double(beyond) / n;
            }
            worst = std::max(worst, std::abs(sum / pixels - truth));
        }
    return worst;
}

TEST(ShadowSampler, PenumbraHasNoBandsAtSixteenSamples) {
    auto jittered = [](uint32_t key, int k) { return shadowDiskSample(key, 0, k, 16); };
    auto fixedSpiral = [](uint32_t, int k) {  // the old sampler: one pattern for every pixel
        return DiskSample{std::sqrt((k + 0.5) / 16), 2.399963229728653 * k};
    };
    double fixedBias = worstBias(fixedSpiral, 64), jitteredBias = worstBias(jittered, 4096);
    // Measured: 0.094 for the fixed spiral (one and a half steps of 1/16: the bands), 0.0025
    // jittered (what is left is the noise of 4096 pixels' means).
    EXPECT_GT(fixedBias, 0.04);
    EXPECT_LT(jitteredBias, 0.01);
}

}  // namespace
}  // namespace rt
