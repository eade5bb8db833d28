// The MIS-compensated distribution (host/lib/prepare/env_compensation.h): per cell, a density
// proportional to max(0, f - mean f) sin(theta), normalised; zero wherever the map is at or below
// its solid-angle mean; the full distribution back for a map with nothing above its mean. The
// sampler's agreement with this table is the chi-square test of kernels/envmap_chi2_test.cpp.
#include "prepare/env_compensation.h"
#include "kernels/piecewise_constant.h"
#include "load/environment_map.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

double joint(const et::EnvDistribution& d, int row, int col) {
    return double(d.table[row]) *
           d.table[etk::etk_dist2d_conditional_pdf(d.height) + size_t(row) * d.width + col];
}

TEST(EnvCompensation, DensityIsTheExcessOverTheMean) {
    const int w = 64, h = 32;
    et::RgbImage img = ett::constant_image(w, h, 1.0f);
    // A bright patch (a "sun") and a dimmer band: the band is below the mean, the patch above.
    for (int y = 8; y < 11; ++y)
        for (int x = 20; x < 24; ++x) {
            float* t = img.at(x, y);
            t[0] = t[1] = t[2] = 200.0f;
        }
    for (int x = 0; x < w; ++x) {
        float* t = img.at(x, 20);
        t[0] = t[1] = t[2] = 3.0f;
    }
    et::DistributionOptions opt;
    opt.blur_sigma = 0.0f;
    const et::EnvMap env = et::make_envmap("patch", img, opt);
    const et::EnvDistribution& full = env.dist;
    const et::EnvDistribution comp = et::compensate_distribution(full);
    ASSERT_EQ(comp.width, w);
    ASSERT_EQ(comp.height, h);
    ASSERT_EQ(comp.table.size(), full.table.size());
    ASSERT_TRUE(comp.has_light());

    // f per cell from the full table, its solid-angle mean, the expected compensated densities.
    double sum_f_sin = 0.0, sum_sin = 0.0;
    std::vector<double> f(size_t(w) * h), expected(size_t(w) * h);
    for (int r = 0; r < h; ++r) {
        const double s = std::sin(M_PI * (r + 0.5) / h);
        for (int c = 0; c < w; ++c) {
            f[size_t(r) * w + c] = joint(full, r, c) / s;
            sum_f_sin += joint(full, r, c);
            sum_sin += s;
        }
    }
    const double mean = sum_f_sin / sum_sin;
    double total = 0.0;
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const double s = std::sin(M_PI * (r + 0.5) / h);
            expected[size_t(r) * w + c] = std::max(0.0, f[size_t(r) * w + c] - mean) * s;
            total += expected[size_t(r) * w + c];
        }
    int positive = 0;
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const double e = expected[size_t(r) * w + c] * (double(w) * h / total);
            const double got = joint(comp, r, c);
            EXPECT_NEAR(got, e, 1e-4 * std::max(1.0, e)) << "cell " << r << ", " << c;
            positive += got > 0.0;
        }
    // Only the bright patch (with its bilinear fringe) keeps mass: the constant background and
    // the dim band at 3x the background are below the mean.
    EXPECT_GT(positive, 0);
    EXPECT_LE(positive, 6 * 7);
    for (int c = 0; c < w; ++c)
        EXPECT_EQ(joint(comp, 20, c), 0.0) << "the dim band is below the mean";
}

TEST(EnvCompensation, NothingAboveTheMeanKeepsTheFullDistribution) {
    const et::EnvMap env = et::make_envmap("constant", ett::constant_image(32, 16, 2.0f), {});
    const et::EnvDistribution comp = et::compensate_distribution(env.dist);
    EXPECT_EQ(comp.table, env.dist.table);
    EXPECT_TRUE(comp.has_light());
    // A black map stays without light.
    const et::EnvMap black = et::make_envmap("black", ett::constant_image(32, 16, 0.0f), {});
    EXPECT_FALSE(et::compensate_distribution(black.dist).has_light());
}

} // namespace
