// 1D and 2D piecewise-constant distributions (kernels/piecewise_constant.h and the table
// builder build_piecewise_constant_1d): binary search edge cases, zero-width cells, densities
// consistent with the cell a sample lands in, all-zero functions.
#include "load/env_distribution.h"
#include "kernels/piecewise_constant.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace {

struct Dist1D {
    std::vector<float> f, pdf, cdf;
    std::vector<double> width_density; // what the CDF's widths hold: see the constructor
    double sum = 0;
    explicit Dist1D(std::vector<float> values) : f(std::move(values)) {
        pdf.resize(f.size());
        cdf.resize(f.size() + 1);
        sum = et::build_piecewise_constant_1d(f.data(), n(), pdf.data(), cdf.data());
        // The CDF gives every cell with mass at least kMinCdfShare of it (the densities stay
        // f n / sum): the density a sample is drawn with is n max(f, share sum) / (their sum).
        double raised = 0.0;
        for (float v : f)
            raised += v > 0.0f ? std::max(double(v), sum * et::kMinCdfShare) : 0.0;
        for (float v : f)
            width_density.push_back(
                v > 0.0f ? n() * std::max(double(v), sum * et::kMinCdfShare) / raised : 0.0);
    }
    int n() const { return static_cast<int>(f.size()); }
    float sample(float u, float* density, int* cell) const {
        return etk::etk_sample_1d(cdf.data(), n(), u, density, cell);
    }
};

// Values that stress the search: 0, every CDF entry and its float neighbours, just below 1.
std::vector<float> edge_uniforms(const Dist1D& d) {
    std::vector<float> u = {0.0f, 1e-30f, 0.5f, ETK_ONE_MINUS_EPS, 0.9999999f, 0.999999f};
    for (float c : d.cdf)
        for (float x : {c, std::nextafter(c, 0.0f), std::nextafter(c, 1.0f)})
            if (x >= 0.0f && x < 1.0f)
                u.push_back(x);
    return u;
}

// The sample lies in the returned cell, which has positive width; its density is the cell's CDF
// width times n (what inversion samples with), within the CDF's rounding of the stored f n / sum;
// x inverts the CDF.
void check_sample(const Dist1D& d, float u) {
    float density = -1;
    int cell = -1;
    const float x = d.sample(u, &density, &cell);
    SCOPED_TRACE("u = " + std::to_string(u) + " (bits " + std::to_string(etk::as_uint(u)) + ")");
    ASSERT_GE(cell, 0);
    ASSERT_LT(cell, d.n());
    ASSERT_TRUE(x >= 0.0f && x < 1.0f) << x;
    EXPECT_EQ(etk::etk_cell_of(x, d.n()), cell) << "x = " << x << " left its cell";
    EXPECT_EQ(density, etk::etk_interval_density(d.cdf.data(), d.n(), cell));
    if (d.sum > 0) {
        // Each CDF entry is within half an ulp (<= 2^-25 below 1) of its exact value.
        EXPECT_NEAR(density, d.width_density[cell], d.n() * 0x1p-24 + 1e-6 * d.width_density[cell]);
        EXPECT_GT(d.cdf[cell + 1], d.cdf[cell]) << "a zero-width cell was chosen";
        EXPECT_GT(density, 0.0f);
        // CDF(x) = cdf[i] + (x n - i) (cdf[i+1] - cdf[i]) should give back u, up to the float
        // rounding of t and of x (a few ulps of x, times the density) and of u itself.
        const double t = static_cast<double>(x) * d.n() - cell;
        const double back = d.cdf[cell] + t * (d.cdf[cell + 1] - d.cdf[cell]);
        EXPECT_NEAR(back, u, 4.0 * 0x1p-24 * (1.0 + density)) << "x " << x << " cell " << cell;
    } else { // no mass: a linear CDF, sampled uniformly (a 2D table gives such a row no mass)
        EXPECT_NEAR(density, 1.0f, 1e-5f);
    }
}

TEST(PiecewiseConstant1D, TablesOfTheFigure2Builder) {
    Dist1D d({1, 0, 3, 0, 0, 4});
    EXPECT_DOUBLE_EQ(d.sum, 8.0);
    const float cdf[] = {0, 0.125f, 0.125f, 0.5f, 0.5f, 0.5f, 1};
    for (int i = 0; i <= d.n(); ++i)
        EXPECT_FLOAT_EQ(d.cdf[i], cdf[i]) << i;
    // Densities over the unit interval: f * n / sum.
    EXPECT_FLOAT_EQ(d.pdf[0], 0.75f);
    EXPECT_FLOAT_EQ(d.pdf[2], 2.25f);
    EXPECT_FLOAT_EQ(d.pdf[5], 3.0f);
    EXPECT_EQ(d.pdf[1], 0.0f);
}

TEST(PiecewiseConstant1D, ZeroWidthCellsAreNeverChosen) {
    const std::vector<std::vector<float>> functions = {
        {1, 0, 3, 0, 0, 4}, {0, 0, 1, 1},      {1, 1, 0, 0},         {0, 0, 0, 5, 0, 0, 0}, {1},
        {1e-30f, 1e30f, 0}, {0, 1e-38f, 0, 1}, {7, 7, 7, 7, 7, 7, 7}};
    for (const auto& f : functions) {
        Dist1D d(f);
        for (float u : edge_uniforms(d))
            check_sample(d, u);
    }
}

TEST(PiecewiseConstant1D, SearchOnExactCdfEntries) {
    Dist1D d({1, 0, 3, 0, 0, 4});
    int cell;
    float density;
    d.sample(0.0f, &density, &cell);
    EXPECT_EQ(cell, 0);
    d.sample(0.125f, &density, &cell); // cdf[1] == cdf[2]: the cell after the run
    EXPECT_EQ(cell, 2);
    d.sample(0.5f, &density, &cell);
    EXPECT_EQ(cell, 5);
    d.sample(ETK_ONE_MINUS_EPS, &density, &cell);
    EXPECT_EQ(cell, 5);
    Dist1D lead({0, 0, 1, 1});
    lead.sample(0.0f, &density, &cell);
    EXPECT_EQ(cell, 2);
    Dist1D trail({1, 1, 0, 0});
    trail.sample(ETK_ONE_MINUS_EPS, &density, &cell);
    EXPECT_EQ(cell, 1);
}

// LuxCore's dead-code case: u so close to 1 that i + t rounds up to the next cell.
TEST(PiecewiseConstant1D, OffsetNeverRoundsIntoTheNextCell) {
    for (int n : {1, 2, 3, 7, 100, 333, 1000, 4097, 65536}) {
        for (int i : {0, n / 2, n - 1})
            for (float t : {0.0f, 0.5f, 0.9999f, ETK_ONE_MINUS_EPS}) {
                const float x = etk::etk_cell_coordinate(i, t, n);
                ASSERT_EQ(etk::etk_cell_of(x, n), i) << "n " << n << " i " << i << " t " << t;
                ASSERT_LT(x, 1.0f);
            }
        std::vector<float> f(n, 1.0f);
        f[n - 1] = 1e-6f; // a tiny last cell: u near 1 lands there
        Dist1D d(f);
        for (float u : edge_uniforms(d))
            check_sample(d, u);
    }
}

// For n a power of two the coordinate is a product by 1/n (no division): the same float as the
// division i + t over n, clamped below the next cell, for every cell of small tables and random
// offsets.
TEST(PiecewiseConstant1D, PowerOfTwoCellCoordinateIsTheDivision) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    for (int n : {1, 2, 4, 64, 512, 1024, 4096, 65536}) {
        for (int k = 0; k < 20000; ++k) {
            const int i = k < n ? k : static_cast<int>(rng() % n);
            const float t = k % 7 == 0 ? ETK_ONE_MINUS_EPS : std::min(U(rng), ETK_ONE_MINUS_EPS);
            const float hi = static_cast<float>(i + 1) / n;
            const float div = std::min((static_cast<float>(i) + t) / n, std::nextafter(hi, 0.0f));
            const float x = etk::etk_cell_coordinate(i, t, n);
            ASSERT_EQ(x, div) << "n " << n << " i " << i << " t " << t;
            ASSERT_EQ(etk::etk_cell_of(x, n), i);
        }
    }
}

TEST(PiecewiseConstant1D, RandomUniformsOnRandomFunctions) {
    std::mt19937 rng(17);
    for (int trial = 0; trial < 50; ++trial) {
        const int n = 1 + static_cast<int>(rng() % 300);
        std::vector<float> f(n);
        for (float& v : f)
            v = rng() % 3 == 0 ? 0.0f
                               : std::ldexp(static_cast<float>(rng() % 1000), -(int)(rng() % 40));
        Dist1D d(f);
        std::uniform_real_distribution<float> uni(0.0f, 1.0f);
        for (int k = 0; k < 200; ++k)
            check_sample(d, std::min(uni(rng), ETK_ONE_MINUS_EPS));
    }
}

// etk_find_interval against the definition (the last cell whose CDF entry is <= u and whose
// successor is larger, i.e. std::upper_bound - 1 over the first n entries) for sizes around
// powers of two up to 65536, on random, peaky, tied and zero-mass functions, at random u and at
// every CDF entry and its neighbours (the search was shortened: the result must not move).
TEST(PiecewiseConstant1D, SearchEqualsUpperBound) {
    std::mt19937 rng(12);
    std::vector<int> sizes = {1,  2,   3,   4,   5,   7,    8,    9,     31,   32,
                              33, 100, 511, 512, 513, 1024, 4096, 65535, 65536};
    for (int n : sizes)
        for (int kind = 0; kind < 4; ++kind) {
            std::vector<float> f(n);
            for (int i = 0; i < n; ++i) {
                switch (kind) {
                case 0:
                    f[i] = static_cast<float>(rng() % 1000);
                    break; // random, some zeros
                case 1:
                    f[i] = rng() % 97 == 0 ? 1e6f : 1e-3f;
                    break; // peaky
                case 2:
                    f[i] = (i / 7) % 2 ? 0.0f : 1.0f;
                    break; // runs of zero mass
                default:
                    f[i] = i == n / 2 ? 1.0f : 0.0f;
                    break; // one cell
                }
            }
            Dist1D d(f);
            std::vector<float> us = edge_uniforms(d);
            std::uniform_real_distribution<float> uni(0.0f, 1.0f);
            for (int k = 0; k < 2000; ++k)
                us.push_back(std::min(uni(rng), ETK_ONE_MINUS_EPS));
            for (float u : us) {
                const int expect = static_cast<int>(
                    std::upper_bound(d.cdf.begin(), d.cdf.begin() + n, u) - d.cdf.begin() - 1);
                ASSERT_EQ(etk::etk_find_interval(d.cdf.data(), n, u), std::max(0, expect))
                    << "n " << n << " kind " << kind << " u " << u;
            }
        }
}

TEST(PiecewiseConstant1D, AllZeroFunctionHasLinearCdfAndIsSampledUniformly) {
    Dist1D d({0, 0, 0, 0});
    EXPECT_EQ(d.sum, 0.0);
    for (int i = 0; i <= 4; ++i)
        EXPECT_FLOAT_EQ(d.cdf[i], i / 4.0f);
    for (float u : edge_uniforms(d))
        check_sample(d, u);
}

TEST(PiecewiseConstant2D, SampleDensityMatchesPdfAtTheSample) {
    // A 16x8 map lit in a block only (no blur): whole rows and columns of zero cells.
    et::RgbImage img = ett::constant_image(16, 8, 0.0f);
    for (int y = 3; y <= 4; ++y)
        for (int x = 5; x <= 9; ++x)
            img.at(x, y)[0] = img.at(x, y)[1] = img.at(x, y)[2] = float(1 + x * y);
    et::DistributionOptions opt;
    opt.blur_sigma = 0.0f;
    const et::EnvDistribution dist = et::build_env_distribution(img, opt);
    ASSERT_EQ(static_cast<int>(dist.table.size()), etk::etk_dist2d_size(16, 8));
    const float* t = dist.table.data();
    // Marginal CDF entries and, per row, conditional CDF entries as uniforms.
    std::vector<float> us = {0.0f, 0.3f, ETK_ONE_MINUS_EPS}, vs = {0.0f, 0.7f, ETK_ONE_MINUS_EPS};
    for (int r = 0; r <= 8; ++r)
        vs.push_back(std::min(t[etk::etk_dist2d_marginal_cdf(8) + r], ETK_ONE_MINUS_EPS));
    for (int r = 0; r < 8; ++r)
        for (int c = 0; c <= 16; ++c)
            us.push_back(std::min(t[etk::etk_dist2d_conditional_cdf(16, 8) + r * 17 + c],
                                  ETK_ONE_MINUS_EPS));
    double mass = 0.0;
    for (float v : vs)
        for (float u : us) {
            float density;
            int row, col;
            const etk::float2 uv =
                etk::etk_sample_2d(t, 16, 8, etk::make_float2(u, v), &density, &row, &col);
            ASSERT_EQ(etk::etk_cell_of(uv.x, 16), col);
            ASSERT_EQ(etk::etk_cell_of(uv.y, 8), row);
            ASSERT_GT(density, 0.0f) << "u " << u << " v " << v;
            ASSERT_EQ(density, etk::etk_pdf_2d(t, 16, 8, uv));
        }
    // The joint density integrates to one over the square.
    for (int r = 0; r < 8; ++r)
        for (int c = 0; c < 16; ++c)
            mass += etk::etk_pdf_2d(t, 16, 8, etk::make_float2((c + 0.5f) / 16, (r + 0.5f) / 8)) /
                    (16.0 * 8.0);
    EXPECT_NEAR(mass, 1.0, 1e-6);
}

} // namespace
