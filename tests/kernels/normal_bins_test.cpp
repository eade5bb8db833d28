// The cosine strategy's bins of normals (kernels/normal_bins.h): the octahedral map and its
// inverse agree, every bin's centre lies in its own bin, every unit vector lies within a few
// degrees of its bin's centre (the tables are built for the centre), and the bins' solid angles
// stay within a small factor of each other (no bin so large that its table fits none of its
// normals).
#include "kernels/normal_bins.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace {

etk::float3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> N(0.0f, 1.0f);
    for (;;) {
        const etk::float3 v = etk::make_float3(N(rng), N(rng), N(rng));
        const float l = etk::length(v);
        if (l > 1e-3f)
            return v / l;
    }
}

TEST(NormalBins, OctahedralMapInvertsAndEveryCentreIsInItsBin) {
    std::mt19937 rng(5);
    float worst = 0.0f;
    for (int i = 0; i < 100000; ++i) {
        const etk::float3 n = random_unit(rng);
        const etk::float3 back = etk::etk_octahedral_dir(etk::etk_octahedral_point(n));
        worst = std::max(worst, etk::length(back - n));
    }
    EXPECT_LT(worst, 1e-5f);
    // The poles and the folded edges.
    for (const etk::float3 n : {etk::make_float3(0, 1, 0), etk::make_float3(0, -1, 0),
                                etk::make_float3(1, 0, 0), etk::make_float3(0, 0, -1)}) {
        const etk::float3 back = etk::etk_octahedral_dir(etk::etk_octahedral_point(n));
        EXPECT_LT(etk::length(back - n), 1e-6f);
    }
    for (int k = 0; k < ETK_NORMAL_BINS; ++k)
        ASSERT_EQ(etk::etk_normal_bin(etk::etk_normal_bin_centre(k)), k);
}

TEST(NormalBins, NormalsLieNearTheirBinsCentreAndBinsAreAlike) {
    std::mt19937 rng(9);
    const int n = 1 << 21;
    std::vector<int> count(ETK_NORMAL_BINS, 0);
    double worst = 0.0;
    for (int i = 0; i < n; ++i) {
        const etk::float3 v = random_unit(rng);
        const int k = etk::etk_normal_bin(v);
        ASSERT_GE(k, 0);
        ASSERT_LT(k, ETK_NORMAL_BINS);
        ++count[k];
        const double c = etk::dot(v, etk::etk_normal_bin_centre(k));
        worst = std::max(worst, std::acos(std::min(1.0, c)));
    }
    // A 32 x 32 octahedral square: the farthest normal 7.5 degrees from its bin's centre (the
    // cells stretched most, along the diamond's edges).
    EXPECT_LT(worst * 180.0 / M_PI, 8.0);
    const auto [lo, hi] = std::minmax_element(count.begin(), count.end());
    const double mean = double(n) / ETK_NORMAL_BINS;
    std::printf("bins: %d .. %d normals of %.0f, farthest %.2f degrees\n", *lo, *hi, mean,
                worst * 180.0 / M_PI);
    // The octahedral map's cells differ in solid angle by up to ~5x: 0.34 .. 1.65 of the mean
    // (sampling noise here ~2%).
    EXPECT_GT(*lo, 0.3 * mean);
    EXPECT_LT(*hi, 1.8 * mean);
}

} // namespace
