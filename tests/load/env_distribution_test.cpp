// host/lib/load/env_distribution: the sampling table of a lat-long map. Checks the table layout of
// kernels/piecewise_constant.h (CDFs monotone from 0 to 1, densities consistent with them), the
// function it samples (the exact cell mean of the bilinear lookup's luminance: a [1 6 1]/8 stencil,
// wrapping in phi and clamped at the poles, times sin(theta) at the row centre), the area
// resampling to a lower resolution, the blur, and the all-black map.
#include "load/env_distribution.h"
#include "kernels/envmap.h"
#include "kernels/piecewise_constant.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

namespace {

// Read access to a table of w x h cells.
// Holds a pointer into the distribution, which must outlive it.
struct Table {
    int w, h;
    const float* t;
    explicit Table(const et::EnvDistribution& d) : w(d.width), h(d.height), t(d.table.data()) {}
    float marginal_pdf(int r) const { return t[r]; }
    float marginal_cdf(int i) const { return t[etk::etk_dist2d_marginal_cdf(h) + i]; }
    float cond_pdf(int r, int c) const {
        return t[etk::etk_dist2d_conditional_pdf(h) + static_cast<size_t>(r) * w + c];
    }
    float cond_cdf(int r, int i) const {
        return t[etk::etk_dist2d_conditional_cdf(w, h) + static_cast<size_t>(r) * (w + 1) + i];
    }
    // Probability of cell (c, r).
    double mass(int c, int r) const {
        return static_cast<double>(marginal_pdf(r)) * cond_pdf(r, c) / (double(w) * h);
    }
};

double sin_row(int r, int h) {
    return std::sin(M_PI * (r + 0.5) / h);
}

// The sampled function of cell (c, r), sin(theta)-weighted: mass times the table's total.
double weighted_f(const et::EnvDistribution& d, int c, int r) {
    return Table(d).mass(c, r) * d.total;
}

void set_grey(et::RgbImage& img, int x, int y, float v) {
    img.at(x, y)[0] = img.at(x, y)[1] = img.at(x, y)[2] = v;
}

et::RgbImage random_map(int w, int h, uint32_t seed, float fraction_lit = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (u(rng) >= fraction_lit)
                continue;
            const float s = std::pow(10.0f, 3.0f * u(rng) - 1.0f);
            for (int c = 0; c < 3; ++c)
                img.at(x, y)[c] = s * u(rng);
        }
    return img;
}

et::EnvDistribution build(const et::RgbImage& img, float blur, int dw = 0, int dh = 0) {
    et::DistributionOptions o;
    o.blur_sigma = blur;
    o.width = dw;
    o.height = dh;
    return et::build_env_distribution(img, o);
}

// Layout, monotone CDFs from 0 to 1, densities that are the CDF steps, finite everywhere.
void expect_valid_table(const et::EnvDistribution& d) {
    const Table t(d);
    ASSERT_EQ(d.table.size(), static_cast<size_t>(etk::etk_dist2d_size(d.width, d.height)));
    for (float v : d.table)
        ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << v;
    auto check_1d = [](auto pdf, auto cdf, int n, const std::string& what) {
        ASSERT_EQ(cdf(0), 0.0f) << what;
        ASSERT_EQ(cdf(n), 1.0f) << what;
        double sum = 0.0;
        for (int i = 0; i < n; ++i) {
            ASSERT_LE(cdf(i), cdf(i + 1)) << what << " entry " << i;
            sum += pdf(i);
        }
        if (sum == 0.0)
            return; // no light: linear CDF, checked elsewhere
        EXPECT_NEAR(sum / n, 1.0, 1e-4) << what << ": densities average to one";
        for (int i = 0; i < n; ++i)
            ASSERT_NEAR(cdf(i + 1) - cdf(i), pdf(i) / n, 2e-6 + 1e-4 * pdf(i) / n)
                << what << " cell " << i;
    };
    check_1d([&](int i) { return t.marginal_pdf(i); }, [&](int i) { return t.marginal_cdf(i); },
             d.height, "marginal");
    for (int r = 0; r < d.height; ++r)
        check_1d([&](int i) { return t.cond_pdf(r, i); }, [&](int i) { return t.cond_cdf(r, i); },
                 d.width, "row " + std::to_string(r));
}

TEST(EnvDistribution, CdfsAreMonotoneAndEndAtOne) {
    for (float blur : {0.0f, 0.5f, 2.0f}) {
        SCOPED_TRACE("blur " + std::to_string(blur));
        const et::EnvDistribution d = build(random_map(96, 48, 1), blur);
        EXPECT_EQ(d.width, 96);
        EXPECT_EQ(d.height, 48);
        EXPECT_TRUE(d.has_light());
        expect_valid_table(d);
    }
    // Sparse: rows and columns of zero cells give flat CDF runs, still monotone.
    expect_valid_table(build(random_map(64, 32, 2, 0.01f), 0.0f));
    expect_valid_table(build(random_map(64, 32, 3, 0.05f), 0.5f, 24, 12));
}

TEST(EnvDistribution, CdfsOfARealMap) {
    ETT_DATA_FILE(path, "envmaps/ennis.hdr");
    const et::RgbImage img = et::read_rgb_image(path);
    expect_valid_table(build(img, 0.5f, 256, 128));
}

TEST(EnvDistribution, OneBrightTexelStaysInItsCellAndTheBilinearStencil) {
    // blur 0: the function is the cell mean of the bilinear lookup, so texel (x, y) spreads over
    // its 3x3 neighbourhood only, [1 6 1]/8 x [1 6 1]/8: 36/64 of it in its own cell.
    const int w = 64, h = 32, x0 = 20, y0 = 12;
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    set_grey(img, x0, y0, 1000.0f);
    const et::EnvDistribution d = build(img, 0.0f);
    expect_valid_table(d);
    const Table t(d);
    double inside = 0.0;
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const bool near = std::abs(c - x0) <= 1 && std::abs(r - y0) <= 1;
            if (near)
                inside += t.mass(c, r);
            else
                ASSERT_EQ(t.mass(c, r), 0.0) << "cell " << c << "," << r;
        }
    EXPECT_NEAR(inside, 1.0, 1e-6);
    const double s0 = sin_row(y0, h), sm = sin_row(y0 - 1, h), sp = sin_row(y0 + 1, h);
    EXPECT_NEAR(t.mass(x0, y0), 36 * s0 / (48 * s0 + 8 * sm + 8 * sp), 1e-5);
    EXPECT_GT(t.mass(x0, y0), 0.5);
    const double centre = t.mass(x0, y0);
    EXPECT_NEAR(t.mass(x0 - 1, y0) / centre, 1.0 / 6, 1e-5);
    EXPECT_NEAR(t.mass(x0 + 1, y0) / centre, 1.0 / 6, 1e-5);
    EXPECT_NEAR(t.mass(x0, y0 - 1) / centre, sm / s0 / 6, 1e-5);
    EXPECT_NEAR(t.mass(x0, y0 + 1) / centre, sp / s0 / 6, 1e-5);
    EXPECT_NEAR(t.mass(x0 + 1, y0 + 1) / centre, sp / s0 / 36, 1e-5);
    EXPECT_NEAR(t.mass(x0 - 1, y0 - 1) / centre, sm / s0 / 36, 1e-5);
    // The total is the sin-weighted sum: luminance 1000 spread by a stencil summing to one.
    EXPECT_NEAR(d.total, 1000.0 * (48 * s0 + 8 * sm + 8 * sp) / 64, 1e-3);
}

TEST(EnvDistribution, StencilWrapsInPhiAndClampsAtThePole) {
    const int w = 32, h = 16;
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    set_grey(img, 0, 0, 1.0f); // top-left texel: its left neighbour is column w-1
    const et::EnvDistribution d = build(img, 0.0f);
    const Table t(d);
    const double centre = t.mass(0, 0);
    ASSERT_GT(centre, 0.0);
    EXPECT_NEAR(t.mass(w - 1, 0) / centre, 1.0 / 6, 1e-5) << "no wrap around in phi";
    EXPECT_NEAR(t.mass(1, 0) / centre, 1.0 / 6, 1e-5);
    // Above row 0 the lookup clamps: row 0 keeps (1 + 6) / 8 of the texel, row 1 gets 1/8.
    EXPECT_NEAR(t.mass(0, 1) / centre, sin_row(1, h) / sin_row(0, h) / 7, 1e-5);
    for (int c = 2; c < w - 1; ++c)
        EXPECT_EQ(t.mass(c, 0), 0.0) << c;
    for (int c = 0; c < w; ++c)
        EXPECT_EQ(t.mass(c, h - 1), 0.0) << "mass wrapped to the other pole at column " << c;
}

// Mean luminance of the bilinear lookup over cell (c, r) of a map-resolution table: midpoints of
// an even grid are exact for a function bilinear in each quadrant of the cell.
double cell_mean_of_lookup(const et::RgbImage& img, int c, int r) {
    const int n = 8;
    double sum = 0.0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const etk::float2 uv = etk::make_float2((c + (i + 0.5f) / n) / img.width,
                                                    (r + (j + 0.5f) / n) / img.height);
            const etk::float3 L = etk::etk_env_lookup_uv(img.rgb.data(), img.width, img.height, uv);
            const float rgb[3] = {L.x, L.y, L.z};
            sum += et::luminance(rgb);
        }
    return sum / (n * n);
}

TEST(EnvDistribution, Blur0IsTheSinWeightedCellMeanOfTheLookup) {
    const et::RgbImage img = random_map(48, 24, 4, 0.1f);
    const et::EnvDistribution d = build(img, 0.0f);
    double total = 0.0;
    for (int r = 0; r < d.height; ++r)
        for (int c = 0; c < d.width; ++c) {
            const double want = cell_mean_of_lookup(img, c, r) * sin_row(r, d.height);
            total += want;
            ASSERT_NEAR(weighted_f(d, c, r), want, 1e-4 * want + 1e-6) << c << "," << r;
        }
    EXPECT_NEAR(d.total, total, 1e-5 * total);
}

TEST(EnvDistribution, DensityPositiveWhereverTheLookupIs) {
    // A texel-sparse map: most cells see no light. Probe each cell on a grid reaching its edges.
    const et::RgbImage img = random_map(64, 32, 5, 0.03f);
    const int probes[] = {0, 1, 3, 5, 7, 9}; // in tenths of a cell, 0.01 and 0.99 at the ends
    for (const auto& res : {std::make_pair(0, 0), std::make_pair(32, 16), std::make_pair(24, 12)})
        for (float blur : {0.0f, 0.5f}) {
            SCOPED_TRACE("blur " + std::to_string(blur) + " res " + std::to_string(res.first));
            const et::EnvDistribution d = build(img, blur, res.first, res.second);
            int lit = 0, dark = 0;
            for (int y = 0; y < img.height; ++y)
                for (int x = 0; x < img.width; ++x)
                    for (int j : probes)
                        for (int i : probes) {
                            const float fx = i == 0 ? 0.01f : i == 9 ? 0.99f : i / 10.0f;
                            const float fy = j == 0 ? 0.01f : j == 9 ? 0.99f : j / 10.0f;
                            const etk::float2 uv =
                                etk::make_float2((x + fx) / img.width, (y + fy) / img.height);
                            const etk::float3 L =
                                etk::etk_env_lookup_uv(img.rgb.data(), img.width, img.height, uv);
                            const float rgb[3] = {L.x, L.y, L.z};
                            const float pdf =
                                etk::etk_pdf_2d(d.table.data(), d.width, d.height, uv);
                            if (et::luminance(rgb) > 0.0f) {
                                ++lit;
                                ASSERT_GT(pdf, 0.0f) << "lit at u " << uv.x << " v " << uv.y;
                            } else {
                                ++dark;
                            }
                        }
            EXPECT_GT(lit, 0);
            EXPECT_GT(dark, lit) << "the map should be mostly dark";
        }
}

// A float CDF near 1 cannot hold the width of a row or texel 1e-10 of the whole: under a sun
// 1e12 x the sky every row after the sun's had zero width, so the map's density was zero over
// half the sky and light sampling alone never saw it. Every cell with light keeps a width now
// (at least 2^-21 of its CDF), and the table stays a valid distribution.
TEST(EnvDistribution, EveryLitCellKeepsAWidthUnderASunOf1e12) {
    et::RgbImage img = ett::constant_image(128, 64, 1.0f);
    set_grey(img, 40, 20, 1e12f);
    set_grey(img, 7, 50, 3e11f);
    for (float blur : {0.0f, 0.5f}) {
        const et::EnvDistribution d = build(img, blur);
        expect_valid_table(d);
        for (int r = 0; r < d.height; ++r)
            for (int c = 0; c < d.width; ++c) {
                const etk::float2 uv =
                    etk::make_float2((c + 0.5f) / d.width, (r + 0.5f) / d.height);
                ASSERT_GT(etk::etk_pdf_2d(d.table.data(), d.width, d.height, uv), 0.0f)
                    << "blur " << blur << " cell " << c << ", " << r;
            }
    }
}

TEST(EnvDistribution, Blur0HasNoMassWhereTheLookupVanishes) {
    // The converse at blur 0 and map resolution: a cell whose lookup is zero everywhere (its own
    // texel and its 8 neighbours black) carries nothing, so samples never land in the dark.
    const et::RgbImage img = random_map(64, 32, 6, 0.03f);
    const et::EnvDistribution d = build(img, 0.0f);
    const Table t(d);
    int empty = 0;
    for (int r = 0; r < 32; ++r)
        for (int c = 0; c < 64; ++c) {
            bool any = false;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const float* p = img.at((c + dx + 64) % 64, std::clamp(r + dy, 0, 31));
                    any = any || p[0] > 0.0f || p[1] > 0.0f || p[2] > 0.0f;
                }
            if (!any) {
                ++empty;
                ASSERT_EQ(t.mass(c, r), 0.0) << c << "," << r;
            } else {
                ASSERT_GT(t.mass(c, r), 0.0) << c << "," << r;
            }
        }
    EXPECT_GT(empty, 64 * 32 / 2);
}

TEST(EnvDistribution, ConstantMapRowsFollowSinTheta) {
    const int w = 40, h = 20;
    const et::EnvDistribution d = build(ett::constant_image(w, h, 2.0f), 0.5f);
    expect_valid_table(d);
    const Table t(d);
    double sum_sin = 0.0;
    for (int r = 0; r < h; ++r)
        sum_sin += sin_row(r, h);
    for (int r = 0; r < h; ++r) {
        EXPECT_NEAR(t.marginal_pdf(r), h * sin_row(r, h) / sum_sin, 1e-5) << r;
        for (int c = 0; c < w; ++c)
            ASSERT_NEAR(t.cond_pdf(r, c), 1.0f, 1e-5f) << r << "," << c;
    }
    // Luminance of grey 2 is 2; the total is the sin-weighted sum over all cells.
    EXPECT_NEAR(d.total, 2.0 * w * sum_sin, 1e-5 * d.total);
    // Symmetric about the equator.
    for (int r = 0; r < h / 2; ++r)
        EXPECT_NEAR(t.marginal_pdf(r), t.marginal_pdf(h - 1 - r), 1e-6) << r;
}

TEST(EnvDistribution, UsesRec709Luminance) {
    // Left half pure red, right half pure green: away from the seams the conditional densities
    // are in the ratio of the luminance weights.
    const int w = 32, h = 8;
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            img.at(x, y)[x < w / 2 ? 0 : 1] = 1.0f;
    const et::EnvDistribution d = build(img, 0.0f);
    const Table t(d);
    for (int r = 0; r < h; ++r)
        EXPECT_NEAR(t.cond_pdf(r, 24) / t.cond_pdf(r, 8), 0.7152 / 0.2126, 1e-4) << r;
}

TEST(EnvDistribution, ExponentSamplesAPowerOfLuminance) {
    // Left half luminance 1, right half 16: with exponent 0.5 the densities away from the seams
    // are in the ratio 4, with 1 in the ratio 16; an exponent out of range is an error.
    const int w = 32, h = 8;
    et::RgbImage img = ett::constant_image(w, h, 1.0f);
    for (int y = 0; y < h; ++y)
        for (int x = w / 2; x < w; ++x)
            img.at(x, y)[0] = img.at(x, y)[1] = img.at(x, y)[2] = 16.0f;
    for (float e : {1.0f, 0.5f, 0.25f}) {
        et::DistributionOptions o;
        o.blur_sigma = 0.0f;
        o.exponent = e;
        const et::EnvDistribution d = et::build_env_distribution(img, o);
        const Table t(d);
        for (int r = 0; r < h; ++r)
            EXPECT_NEAR(t.cond_pdf(r, 24) / t.cond_pdf(r, 8), std::pow(16.0, e), 1e-3) << e;
    }
    et::DistributionOptions bad;
    bad.exponent = 1.5f;
    EXPECT_THROW(et::build_env_distribution(img, bad), et::Error);
    bad.exponent = 0.0f;
    EXPECT_THROW(et::build_env_distribution(img, bad), et::Error);
}

TEST(EnvDistribution, ResamplingToHalfResolutionAveragesCells) {
    // Area resampling by 2: each cell is the mean of the 2x2 full-resolution (unweighted)
    // cells, then weighted by sin(theta) at its own row centre.
    const int w = 64, h = 32;
    const et::RgbImage img = random_map(w, h, 7, 0.3f);
    for (float blur : {0.0f, 0.5f}) {
        SCOPED_TRACE("blur " + std::to_string(blur));
        const et::EnvDistribution full = build(img, blur);
        const et::EnvDistribution half = build(img, blur, w / 2, h / 2);
        ASSERT_EQ(half.width, w / 2);
        ASSERT_EQ(half.height, h / 2);
        expect_valid_table(half);
        double total = 0.0;
        for (int r = 0; r < h / 2; ++r)
            for (int c = 0; c < w / 2; ++c) {
                double mean = 0.0;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx)
                        mean +=
                            weighted_f(full, 2 * c + dx, 2 * r + dy) / sin_row(2 * r + dy, h) / 4;
                const double want = mean * sin_row(r, h / 2);
                total += want;
                ASSERT_NEAR(weighted_f(half, c, r), want, 1e-4 * want + 1e-6) << c << "," << r;
            }
        EXPECT_NEAR(half.total, total, 1e-5 * total);
    }
}

TEST(EnvDistribution, ResamplingToAnyResolutionKeepsTheUnweightedMass) {
    // 64x32 -> 48x20 (ratios 4/3 and 8/5): area weights conserve the integral of the function.
    const et::RgbImage img = random_map(64, 32, 8, 0.2f);
    const et::EnvDistribution full = build(img, 0.0f), low = build(img, 0.0f, 48, 20);
    expect_valid_table(low);
    double mass_full = 0.0, mass_low = 0.0;
    for (int r = 0; r < 32; ++r)
        for (int c = 0; c < 64; ++c)
            mass_full += weighted_f(full, c, r) / sin_row(r, 32) / (64.0 * 32);
    for (int r = 0; r < 20; ++r)
        for (int c = 0; c < 48; ++c)
            mass_low += weighted_f(low, c, r) / sin_row(r, 20) / (48.0 * 20);
    EXPECT_NEAR(mass_low, mass_full, 1e-4 * mass_full);
}

TEST(EnvDistribution, BlurSpreadsSymmetricallyAndKeepsTheTotal) {
    const int w = 64, h = 32, x0 = 30, y0 = 16;
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    set_grey(img, x0, y0, 1.0f);
    const et::EnvDistribution sharp = build(img, 0.0f), soft = build(img, 1.0f);
    const Table ts(sharp), tb(soft);
    EXPECT_LT(tb.mass(x0, y0), ts.mass(x0, y0));
    EXPECT_EQ(ts.mass(x0 + 2, y0), 0.0);
    EXPECT_GT(tb.mass(x0 + 2, y0), 0.0);
    EXPECT_GT(tb.mass(x0, y0 + 2), 0.0);
    EXPECT_NEAR(tb.mass(x0 - 2, y0), tb.mass(x0 + 2, y0), 1e-7);
    EXPECT_NEAR(tb.mass(x0 - 3, y0 + 1), tb.mass(x0 + 3, y0 + 1), 1e-7);
    // Normalised kernel: near the equator the sin-weighted total barely moves.
    EXPECT_NEAR(soft.total / sharp.total, 1.0, 0.01);
}

TEST(EnvDistribution, AllBlackMapHasAValidZeroDistribution) {
    for (const auto& res : {std::make_pair(0, 0), std::make_pair(16, 8)})
        for (float blur : {0.0f, 0.5f}) {
            const et::EnvDistribution d =
                build(ett::constant_image(32, 16, 0.0f), blur, res.first, res.second);
            EXPECT_EQ(d.total, 0.0);
            EXPECT_FALSE(d.has_light());
            expect_valid_table(d);
            const Table t(d);
            for (int r = 0; r < d.height; ++r) {
                EXPECT_EQ(t.marginal_pdf(r), 0.0f);
                EXPECT_FLOAT_EQ(t.marginal_cdf(r), float(r) / d.height);
                for (int c = 0; c < d.width; ++c) {
                    EXPECT_EQ(t.cond_pdf(r, c), 0.0f);
                    EXPECT_FLOAT_EQ(t.cond_cdf(r, c), float(c) / d.width);
                }
            }
            // The kernels' lookups stay finite; the map's has_light (false) makes the sample's
            // and the evaluated densities zero (the table alone is uniform: linear CDFs).
            etk::EtkEnvMap env{};
            env.dist_w = d.width;
            env.dist_h = d.height;
            env.rot_cos = 1.0f;
            env.has_light = d.has_light() ? 1 : 0;
            for (float v : {0.0f, 0.3f, 0.999f}) {
                float density = -1.0f;
                int row, col;
                const etk::float2 uv =
                    etk::etk_sample_2d(d.table.data(), d.width, d.height, etk::make_float2(0.5f, v),
                                       &density, &row, &col);
                EXPECT_NEAR(density, 1.0f, 1e-5f) << "the table alone is uniform";
                EXPECT_TRUE(std::isfinite(uv.x) && std::isfinite(uv.y));
                const etk::EtkEnvSample s =
                    etk::etk_env_sample(d.table.data(), env, etk::make_float2(0.5f, v));
                EXPECT_EQ(s.pdf, 0.0f);
                EXPECT_EQ(etk::etk_env_pdf(d.table.data(), env, s.dir), 0.0f);
            }
        }
}

TEST(EnvDistribution, ThreadsGiveTheSameTable) {
    const et::RgbImage img = random_map(64, 128, 9, 0.5f);
    et::DistributionOptions one, four;
    four.threads = 4;
    const et::EnvDistribution a = et::build_env_distribution(img, one),
                              b = et::build_env_distribution(img, four);
    EXPECT_EQ(a.table, b.table);
    EXPECT_EQ(a.total, b.total);
    one.width = four.width = 48;
    one.height = four.height = 96;
    EXPECT_EQ(et::build_env_distribution(img, one).table,
              et::build_env_distribution(img, four).table);
}

// Every finite, non-negative map bounded by kMaxRadiance has a finite, normalised table
// (fuzz finding F6: a grey TIFF of denormal texels, ~1e-44, made densities n / sum with a sum so
// small that n / sum overflowed float: +Inf densities, NaN where f was 0). Tiny, huge and mixed
// maps, with and without blur and resampling.
TEST(EnvDistribution, TinyAndHugeTexelsGiveFiniteNormalisedTables) {
    const float tiny[] = {std::numeric_limits<float>::denorm_min(), 8.68805e-44f,
                          std::numeric_limits<float>::min(), 1e-30f};
    std::vector<std::pair<std::string, et::RgbImage>> maps;
    for (float v : tiny) {
        et::RgbImage img = ett::constant_image(16, 8, 0.0f);
        for (int y = 0; y < 5; ++y) // the shape of F6: a few lit columns in the upper rows
            for (int x = 0; x < 16; x += 4)
                set_grey(img, x, y, v * (1 + x + y));
        char value[32];
        std::snprintf(value, sizeof value, "%g", double(v));
        maps.push_back({std::string("sparse ") + value, img});
        maps.push_back({std::string("constant ") + value, ett::constant_image(16, 8, v)});
    }
    maps.push_back({"max radiance", ett::constant_image(64, 32, et::kMaxRadiance)});
    et::RgbImage mixed = random_map(64, 32, 3, 0.5f);
    for (int x = 0; x < 64; x += 3)
        set_grey(mixed, x, x % 32, x % 2 ? et::kMaxRadiance : tiny[0]);
    maps.push_back({"mixed", mixed});
    for (const auto& [name, img] : maps)
        for (float blur : {0.0f, 0.5f, 4.0f})
            for (int dw : {0, 7}) {
                SCOPED_TRACE(name + ", blur " + std::to_string(blur) + ", width " +
                             std::to_string(dw));
                const et::EnvDistribution d = build(img, blur, dw, dw ? 5 : 0);
                ASSERT_TRUE(std::isfinite(d.total));
                expect_valid_table(d);
            }
}

} // namespace
