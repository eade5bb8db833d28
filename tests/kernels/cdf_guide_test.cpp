// Guide tables of the CDFs (cutpoint method: kernels/piecewise_constant.h
// etk_find_interval_guided, host/lib/load/env_distribution.cpp build_cdf_guide): the guided
// search must return exactly the interval of the plain binary search for every u in [0, 1], so
// a sample's direction, density and cell do not change; the 2D tables built by the distribution
// builder and by the MIS compensation carry guides that agree with their own CDFs; and samples
// drawn in batches (etk_env_sample_batch, the sample_lights stage) equal those drawn one by one.
#include "kernels/envmap.h"
#include "kernels/piecewise_constant.h"
#include "load/env_distribution.h"
#include "prepare/env_compensation.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace {

struct Guided1D {
    std::vector<float> f, pdf, cdf, guide;
    explicit Guided1D(std::vector<float> values) : f(std::move(values)) {
        const int n = static_cast<int>(f.size());
        pdf.resize(n);
        cdf.resize(n + 1);
        et::build_piecewise_constant_1d(f.data(), n, pdf.data(), cdf.data());
        guide.assign(etk::etk_guide_cells(n) + 1, -1.0f);
        et::build_cdf_guide(cdf.data(), n, guide.data());
    }
    int n() const { return static_cast<int>(f.size()); }
};

// Uniforms that stress both searches: 0 and -0, the smallest floats, every CDF entry and its
// float neighbours, every guide cell's start k/K and its neighbours, just below 1, and 1.
std::vector<float> edge_uniforms(const Guided1D& d) {
    std::vector<float> u = {0.0f, -0.0f, 1e-45f, 1e-30f, 0.5f, ETK_ONE_MINUS_EPS, 0.9999999f, 1.0f};
    auto add = [&](float c) {
        for (float x : {c, std::nextafter(c, 0.0f), std::nextafter(c, 2.0f)})
            if (x >= 0.0f && x <= 1.0f)
                u.push_back(x);
    };
    for (float c : d.cdf)
        add(c);
    const int K = etk::etk_guide_cells(d.n());
    for (int k = 0; k <= K; ++k)
        add(static_cast<float>(k) / K);
    return u;
}

std::vector<float> make_function(int n, int kind, std::mt19937& rng) {
    std::vector<float> f(n);
    for (int i = 0; i < n; ++i) {
        switch (kind) {
        case 0:
            f[i] = static_cast<float>(rng() % 1000);
            break; // random, some zeros
        case 1:
            f[i] = rng() % 97 == 0 ? 1e6f : 1e-3f;
            break; // peaky: one guide cell spans many tiny intervals
        case 2:
            f[i] = (i / 7) % 2 ? 0.0f : 1.0f;
            break; // runs of zero mass (equal CDF entries)
        case 3:
            f[i] = i == n / 2 ? 1.0f : 0.0f;
            break; // all mass in one cell
        case 4:
            f[i] = 0.0f;
            break; // no mass: linear CDF
        default:
            f[i] = std::ldexp(static_cast<float>(rng() % 1000), -static_cast<int>(rng() % 60));
            break; // masses over 18 orders of magnitude
        }
    }
    return f;
}

TEST(CdfGuide, TableIsThePlainSearchAtEachCellStart) {
    std::mt19937 rng(7);
    for (int n : {1, 2, 3, 4, 5, 8, 9, 100, 1024, 1025})
        for (int kind = 0; kind < 6; ++kind) {
            Guided1D d(make_function(n, kind, rng));
            const int K = etk::etk_guide_cells(n);
            ASSERT_EQ(K & (K - 1), 0) << "a power of two";
            ASSERT_LE(K, std::max(1, n / 2));
            for (int k = 0; k < K; ++k)
                ASSERT_EQ(d.guide[k], static_cast<float>(etk::etk_find_interval(
                                          d.cdf.data(), n, static_cast<float>(k) / K)))
                    << "n " << n << " kind " << kind << " k " << k;
            ASSERT_EQ(d.guide[K], static_cast<float>(n - 1));
        }
}

// The guide cells' count, a shift of the leading zeros, is the largest power of two <= n/2 (1 for
// n < 4), as the loop it replaced computed it.
TEST(CdfGuide, GuideCellsAreTheLargestPowerOfTwoAtMostHalfOfN) {
    for (int n = 1; n <= 70000; ++n) {
        int k = 1;
        while (4 * k <= n)
            k *= 2;
        ASSERT_EQ(etk::etk_guide_cells(n), k) << "n " << n;
    }
}

// The acceptance test of the guides: the same interval as etk_find_interval, sizes 1 ... 65536.
TEST(CdfGuide, GuidedSearchEqualsPlainSearch) {
    std::mt19937 rng(12);
    const std::vector<int> sizes = {1,  2,   3,   4,   5,   7,    8,    9,     31,   32,
                                    33, 100, 511, 512, 513, 1024, 4096, 65535, 65536};
    long checked = 0;
    for (int n : sizes)
        for (int kind = 0; kind < 6; ++kind) {
            Guided1D d(make_function(n, kind, rng));
            std::vector<float> us = edge_uniforms(d);
            std::uniform_real_distribution<float> uni(0.0f, 1.0f);
            for (int k = 0; k < 2000; ++k)
                us.push_back(std::min(uni(rng), ETK_ONE_MINUS_EPS));
            for (float u : us) {
                ASSERT_EQ(etk::etk_find_interval_guided(d.cdf.data(), n, d.guide.data(), u),
                          etk::etk_find_interval(d.cdf.data(), n, u))
                    << "n " << n << " kind " << kind << " u " << u;
                ++checked;
            }
        }
    EXPECT_GT(checked, 200000);
}

// The 2D sample with the guides (etk_sample_2d) against the same inversion done with the plain
// searches (etk_sample_1d on the marginal, then on the row): bit-identical point, density, cell.
void expect_same_as_plain(const et::EnvDistribution& d, uint32_t seed) {
    const int w = d.width, h = d.height;
    ASSERT_EQ(d.table.size(), static_cast<size_t>(etk::etk_dist2d_size(w, h)));
    ASSERT_EQ(d.table.size(), et::distribution_table_entries(w, h));
    const float* t = d.table.data();
    // The guides stored in the table are those of its own CDFs.
    std::vector<float> g(etk::etk_guide_cells(std::max(w, h)) + 1);
    et::build_cdf_guide(t + etk::etk_dist2d_marginal_cdf(h), h, g.data());
    for (int k = 0; k <= etk::etk_guide_cells(h); ++k)
        ASSERT_EQ(t[etk::etk_dist2d_marginal_guide(w, h) + k], g[k]) << "marginal, k " << k;
    for (int r = 0; r < h; ++r) {
        et::build_cdf_guide(etk::etk_dist2d_row_cdf(t, w, h, r), w, g.data());
        for (int k = 0; k <= etk::etk_guide_cells(w); ++k)
            ASSERT_EQ(etk::etk_dist2d_row_guide(t, w, h, r)[k], g[k]) << "row " << r << " k " << k;
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    std::vector<float> us = {0.0f, 0.25f, 0.5f, ETK_ONE_MINUS_EPS};
    for (int i = 0; i < 300; ++i)
        us.push_back(std::min(uni(rng), ETK_ONE_MINUS_EPS));
    for (int r = 0; r <= h; ++r) // marginal CDF entries: row boundaries
        us.push_back(std::min(t[etk::etk_dist2d_marginal_cdf(h) + r], ETK_ONE_MINUS_EPS));
    for (float v : us)
        for (int j = 0; j < 40; ++j) {
            const float u = us[(j * 7919 + static_cast<int>(v * 1e6f)) % us.size()];
            float density, pv, pu;
            int row, col, prow, pcol;
            const etk::float2 uv =
                etk::etk_sample_2d(t, w, h, etk::make_float2(u, v), &density, &row, &col);
            const float y =
                etk::etk_sample_1d(t + etk::etk_dist2d_marginal_cdf(h), h, v, &pv, &prow);
            const float x =
                etk::etk_sample_1d(etk::etk_dist2d_row_cdf(t, w, h, prow), w, u, &pu, &pcol);
            ASSERT_EQ(row, prow) << "u " << u << " v " << v;
            ASSERT_EQ(col, pcol) << "u " << u << " v " << v;
            ASSERT_EQ(uv.x, x);
            ASSERT_EQ(uv.y, y);
            ASSERT_EQ(density, pv * pu);
        }
    // The sample_lights stage's batches (etk_env_sample_batch) give each sample's bits.
    etk::EtkEnvMap env{};
    env.tex_w = env.dist_w = w;
    env.tex_h = env.dist_h = h;
    env.scale = 1.0f;
    env.rot_cos = std::cos(0.3f);
    env.rot_sin = std::sin(0.3f);
    env.has_light = 1;
    std::vector<etk::float2> xi;
    for (size_t i = 0; i < us.size(); ++i)
        xi.push_back(etk::make_float2(us[(i * 7919) % us.size()], us[i]));
    xi.resize((xi.size() + ETK_LIGHT_BATCH - 1) / ETK_LIGHT_BATCH * ETK_LIGHT_BATCH,
              etk::make_float2(0.5f, 0.5f));
    for (size_t b = 0; b < xi.size(); b += ETK_LIGHT_BATCH) {
        etk::EtkEnvSample batch[ETK_LIGHT_BATCH];
        float xu[ETK_LIGHT_BATCH], xv[ETK_LIGHT_BATCH];
        for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
            xu[k] = xi[b + k].x;
            xv[k] = xi[b + k].y;
        }
        etk::etk_env_sample_batch(t, env, xu, xv, batch);
        for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
            const etk::EtkEnvSample one = etk::etk_env_sample(t, env, xi[b + k]);
            SCOPED_TRACE("u " + std::to_string(xi[b + k].x) + " v " + std::to_string(xi[b + k].y));
            ASSERT_EQ(batch[k].row, one.row);
            ASSERT_EQ(batch[k].col, one.col);
            ASSERT_EQ(batch[k].uv.x, one.uv.x);
            ASSERT_EQ(batch[k].uv.y, one.uv.y);
            ASSERT_EQ(batch[k].pdf, one.pdf);
            ASSERT_EQ(batch[k].dir.x, one.dir.x);
            ASSERT_EQ(batch[k].dir.y, one.dir.y);
            ASSERT_EQ(batch[k].dir.z, one.dir.z);
        }
    }
}

et::RgbImage random_map(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float v = y >= h / 3 && y < h / 2 ? 0.0f : std::pow(U(rng), 8.0f); // black band
            img.at(x, y)[0] = img.at(x, y)[1] = img.at(x, y)[2] = v;
        }
    img.at(w / 5, h / 5)[1] = 1e5f; // a sun
    return img;
}

TEST(CdfGuide, SampleTwoDEqualsPlainInversion) {
    et::DistributionOptions opt;
    opt.blur_sigma = 0.0f; // rows of zero mass stay zero
    opt.threads = 1;
    for (auto [w, h] : {std::pair{64, 32}, {1, 1}, {1, 7}, {9, 1}, {3, 2}, {100, 37}}) {
        SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
        const et::EnvDistribution d = et::build_env_distribution(random_map(w, h, w * 31 + h), opt);
        expect_same_as_plain(d, 1);
        // The MIS-compensated twin builds its own guides.
        const et::EnvDistribution c = et::compensate_distribution(d);
        expect_same_as_plain(c, 2);
    }
    // No light at all: linear CDFs everywhere.
    expect_same_as_plain(et::build_env_distribution(ett::constant_image(16, 8, 0.0f), opt), 3);
    // Resampled to another resolution (the builder's other path through finish_row).
    opt.width = 48;
    opt.height = 20;
    expect_same_as_plain(et::build_env_distribution(random_map(64, 32, 5), opt), 4);
}

// The sample_lights stage's radiance (etk_env_radiance_batch, per channel over arrays) gives each
// sample the bits of the one-by-one lookup (etk_env_radiance_uv): on a map of odd size, at
// random points and at the edges where the lookup wraps in u and clamps at the poles.
TEST(CdfGuide, RadianceBatchEqualsOneByOneLookup) {
    const int w = 37, h = 19;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> value(0.0f, 4.0f), unit(0.0f, 1.0f);
    std::vector<float> texels(3 * w * h);
    for (float& t : texels)
        t = value(rng);
    etk::EtkEnvMap env{};
    env.tex_w = env.dist_w = w;
    env.tex_h = env.dist_h = h;
    env.scale = 1.7f;
    env.has_light = 1;
    std::vector<float> us = {0.0f, 0.5f / w, 1.0f - 0.5f / w, ETK_ONE_MINUS_EPS, 0.25f};
    std::vector<float> vs = {0.0f, 0.5f / h, 1.0f - 0.5f / h, ETK_ONE_MINUS_EPS, 0.75f};
    std::vector<float> u, v;
    for (float a : us)
        for (float b : vs) {
            u.push_back(a);
            v.push_back(b);
        }
    while (u.size() % ETK_LIGHT_BATCH != 0 || u.size() < 8 * ETK_LIGHT_BATCH) {
        u.push_back(unit(rng));
        v.push_back(unit(rng));
    }
    for (size_t b = 0; b < u.size(); b += ETK_LIGHT_BATCH) {
        float r[ETK_LIGHT_BATCH], g[ETK_LIGHT_BATCH], bl[ETK_LIGHT_BATCH];
        etk::etk_env_radiance_batch(texels.data(), env, &u[b], &v[b], r, g, bl);
        for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
            const etk::float3 one =
                etk::etk_env_radiance_uv(texels.data(), env, etk::make_float2(u[b + k], v[b + k]));
            SCOPED_TRACE("u " + std::to_string(u[b + k]) + " v " + std::to_string(v[b + k]));
            ASSERT_EQ(r[k], one.x);
            ASSERT_EQ(g[k], one.y);
            ASSERT_EQ(bl[k], one.z);
        }
    }
}

} // namespace
