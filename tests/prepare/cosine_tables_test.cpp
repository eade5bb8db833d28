// The cosine strategy's light tables (host/lib/prepare/cosine_tables.h): each bin's weights over
// the map's regions must bound the map's light in the region times the clamped cosine to every
// normal of the bin -- in map space, so the map's rotation is applied -- without being loose, and
// its table mix them with the map's own masses for the defensive share; and a light sample drawn
// from a bin's table must have exactly the density it reports (chi-square over the map's
// distribution cells, where both are piecewise constant in the lat-long square), integrate to one
// and reach every direction the map lights.
#include "prepare/cosine_tables.h"

#include "guide_sampling_check.h"
#include "kernels/latlong.h"
#include "kernels/normal_bins.h"
#include "kernels/visibility_guide.h"
#include "load/env_distribution.h"
#include "prepare/visibility_tables.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace {

constexpr int K = ETK_GUIDE_REGIONS;
constexpr float kAlpha = 0.1f;
constexpr int kBins[] = {0, 300, 527, ETK_NORMAL_BINS - 1}; // edges, the upper and lower side

struct Map {
    et::EnvDistribution dist;
    std::vector<float> regions, tables;
    etk::EtkEnvMap env{};
};

Map make_map(const et::RgbImage& img, float rotation) {
    Map m;
    et::DistributionOptions o;
    o.threads = 1;
    m.dist = et::build_env_distribution(img, o);
    m.env.tex_w = m.env.dist_w = img.width;
    m.env.tex_h = m.env.dist_h = img.height;
    m.env.scale = 1.0f;
    m.env.rot_cos = std::cos(rotation);
    m.env.rot_sin = std::sin(rotation);
    m.env.has_light = 1;
    m.regions = et::guide_region_tables(m.dist.table, img.width, img.height);
    m.tables = et::cosine_bin_tables(m.dist.table, m.regions, m.env, kAlpha);
    return m;
}

// A w x h map of random radiance in [0.05, 1.05) with a sun of radiance `sun` a fifth of the way
// down.
et::RgbImage random_map(int w, int h, uint32_t seed, float sun) {
    et::RgbImage img;
    img.width = w;
    img.height = h;
    img.rgb.resize(static_cast<size_t>(w) * h * 3);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    for (float& x : img.rgb)
        x = 0.05f + U(rng);
    for (int k = 0; k < 3; ++k)
        img.rgb[3 * (static_cast<size_t>(h / 5) * w + w / 3) + k] = sun;
    return img;
}

// A map's tables as the kernels read them, every bin a slot.
struct Sampling {
    etk::EtkScene S{};
    etk::EtkParams p{};
    explicit Sampling(const Map& m) {
        S.env_dist = m.dist.table.data();
        S.guide_regions = m.regions.data();
        S.guide_cells = m.tables.data();
        p.env = m.env;
        p.guide_slots = ETK_NORMAL_BINS;
        p.guide_ready = 1;
    }
};

// 2^20 light samples of `bin`: each with the density it reports, the densities integrating to
// one, the histogram fitting them (chi-square, two bins a test). Returns the check.
ett::GuideSamplingCheck expect_samples_match_their_density(const Sampling& t, int bin,
                                                           uint32_t seed) {
    const ett::GuideSamplingCheck g =
        ett::check_guide_sampling(t.S, t.p, bin, 1 << 20, seed, ett::sidak_alpha(0.01, 2));
    EXPECT_EQ(g.bad, 0) << "bin " << bin;
    EXPECT_EQ(g.mismatched, 0) << "bin " << bin;
    EXPECT_NEAR(g.integral, 1.0, 1e-4) << "bin " << bin;
    EXPECT_TRUE(g.chi.passed) << "bin " << bin << ": " << g.chi.report;
    return g;
}

// The bins' weights bound the light times max(0, n . w) of every normal n of the bin, region by
// region (conservative: no direction a vertex is lit from gets a density far below its share of
// the light), summed here texel by texel from the distribution's masses at normals drawn all over
// the bin's square, the map rotated (so the bound must be taken in map space); and they are not
// loose: their sum is within 1.35x of the bin centre's own clamped-cosine light. The tables are
// then alpha x the map's region masses + (1 - alpha) x the weights' proportions.
TEST(CosineTables, BoundTheClampedCosineOfEveryNormalOfTheBin) {
    const int w = 128, h = 64;
    const Map m = make_map(random_map(w, h, 11, 300.0f), 0.7f);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    const std::vector<double> weights = et::cosine_bin_weights(m.dist.table, m.env);
    // Each texel's mass in the distribution, its region and, a quarter of the mass each, the
    // directions (map space) at its four corners, just inside: a light sample lands anywhere in
    // the texel, so the bound must hold to its edges.
    const float* ccdf = m.dist.table.data() + etk::etk_dist2d_conditional_cdf(w, h);
    std::vector<double> mass;
    std::vector<etk::float3> dir;
    std::vector<int> region;
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const double mt = double(m.dist.table[r]) / h *
                              (double(ccdf[r * (w + 1) + c + 1]) - double(ccdf[r * (w + 1) + c]));
            const int R =
                etk::etk_guide_region(m.env, etk::make_float2((c + 0.5f) / w, (r + 0.5f) / h));
            for (float a : {0.01f, 0.99f})
                for (float b : {0.01f, 0.99f}) {
                    mass.push_back(0.25 * mt);
                    dir.push_back(
                        etk::etk_latlong_to_dir(etk::make_float2((c + a) / w, (r + b) / h)));
                    region.push_back(R);
                }
        }
    auto clamped = [&](etk::float3 n_world) {
        const etk::float3 n = etk::etk_world_to_env(m.env, n_world);
        std::vector<double> I(K, 0.0);
        for (size_t t = 0; t < mass.size(); ++t)
            I[region[t]] += mass[t] * std::max(0.0, double(etk::dot(n, dir[t])));
        return I;
    };
    for (int bin : kBins) {
        const double* P = weights.data() + static_cast<size_t>(bin) * K;
        int below = 0;
        double worst = 0.0;
        for (int j = 0; j < 64; ++j) {
            const int side = ETK_NORMAL_BIN_SIDE;
            const etk::float2 q =
                etk::make_float2((bin % side + U(rng)) / side, (bin / side + U(rng)) / side);
            const etk::float3 n = etk::etk_octahedral_dir(q);
            ASSERT_EQ(etk::etk_normal_bin(n), bin);
            const std::vector<double> I = clamped(n);
            for (int R = 0; R < K; ++R)
                if (I[R] > P[R] * (1.0 + 1e-5) + 1e-12) {
                    ++below;
                    worst = std::max(worst, I[R] / P[R]);
                }
        }
        EXPECT_EQ(below, 0) << "bin " << bin << ": a region's weight below a normal's light, by "
                            << worst << "x";
        const std::vector<double> Ic = clamped(etk::etk_normal_bin_centre(bin));
        double sum_p = 0.0, sum_c = 0.0;
        for (int R = 0; R < K; ++R) {
            sum_p += P[R];
            sum_c += Ic[R];
        }
        std::printf("bin %d: weights %.4f, the centre's clamped-cosine light %.4f\n", bin, sum_p,
                    sum_c);
        EXPECT_LT(sum_p, 1.35 * sum_c) << "bin " << bin;
        // The table: alpha M_R + (1 - alpha) P_R / sum P.
        const float* cdf = m.tables.data() + static_cast<size_t>(bin) * ETK_GUIDE_CELL_FLOATS;
        for (int R = 0; R < K; ++R)
            ASSERT_NEAR(double(cdf[R + 1]) - double(cdf[R]),
                        kAlpha * m.regions[R] + (1.0 - kAlpha) * P[R] / sum_p, 2e-6)
                << "bin " << bin << " region " << R;
        EXPECT_EQ(cdf[ETK_GUIDE_LIGHT_COUNT], 1.0f);
    }
}

// A light sample from a bin's table (etk_guide_sample, as the cosine strategy draws it) against
// the density the tables give: chi-square over the distribution's cells; the density integrates
// to one; E[1 / pdf] is the sphere's area (the defensive share reaches everything the map lights,
// the bin's far side included).
TEST(CosineTables, SamplesMatchTheirDensity) {
    const Map m = make_map(random_map(96, 48, 3, 400.0f), -1.1f);
    const Sampling t(m);
    for (int bin : {kBins[1], kBins[3]}) {
        const ett::GuideSamplingCheck g = expect_samples_match_their_density(t, bin, 17u + bin);
        EXPECT_NEAR(g.mean_inv_pdf, 4.0 * M_PI, 5.0 * g.sd_inv_pdf) << "bin " << bin;
    }
}

// The same under a sun 1e11 x its sky, where a float CDF cannot hold the widths of the rows after
// the sun's. The region tables took the rows' stored densities, so the bins drew directions the
// map's density (the CDF widths) calls impossible: mismatched samples, and the cosine strategy
// 9% dark. And the map's CDF keeps a width for every row and texel with light, so the samples
// still reach the whole sphere (mean 1/pdf 4 pi; without, the sky below the sun is never drawn).
TEST(CosineTables, SamplesMatchTheirDensityUnderASunOf1e11) {
    const Map m = make_map(random_map(96, 48, 3, 1e11f), 0.4f);
    const Sampling t(m);
    for (int bin : {kBins[2], kBins[3]}) {
        expect_samples_match_their_density(t, bin, 31u + bin);
        // Every cell keeps a density (the mean of 1/pdf is too heavy-tailed to show it here).
        const int w = m.env.dist_w, h = m.env.dist_h;
        for (int r = 0; r < h; ++r)
            for (int c = 0; c < w; ++c) {
                const etk::float2 uv = etk::make_float2((c + 0.5f) / w, (r + 0.5f) / h);
                ASSERT_GT(etk::etk_pdf_2d(t.S.env_dist, w, h, uv) *
                              etk::etk_guide_factor(t.S, t.p, bin, uv),
                          0.0f)
                    << "bin " << bin << " cell " << c << ", " << r;
            }
    }
}

} // namespace
