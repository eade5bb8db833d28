// Learned portals (kernels/portal_guide.h): a point drawn from the table must leave the box, seen
// from any point inside, through each cell as often as the table says (chi-square over the
// cells, where expected counts are exact because the ray from a point inside the box leaves it
// exactly once); the solid-angle density must integrate to one over the sphere from any point
// inside, near a face and near a corner included; and a cell of zero probability must have zero
// density.
#include "chi2.h"
#include "kernels/portal_guide.h"
#include "prepare/visibility_tables.h"
#include "render/visibility_cache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace {

constexpr int kTests = 3; // chi-square tests in this file, family-wise alpha 0.01

// A table over the box [lo, hi] (enlarged as the renderer does) with random cell probabilities:
// one face empty, every third cell empty, a few cells `bright` times brighter (windows).
std::vector<float> make_table(uint32_t seed, double bright) {
    const float lo[3] = {-1.0f, 0.0f, 2.0f}, hi[3] = {5.0f, 3.0f, 3.5f};
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::vector<double> w(ETK_PORTAL_CELLS);
    const int per_face = ETK_PORTAL_N * ETK_PORTAL_N;
    for (int k = 0; k < ETK_PORTAL_CELLS; ++k)
        w[k] = (k / per_face == 3 || k % 3 == 0) ? 0.0 : (U(rng) < 0.01 ? bright : U(rng));
    std::vector<float> t(etk::etk_portal_size(1), 0.0f);
    et::write_portal_table(et::guide_portal_box(lo, hi), {0.5f}, w, t.data());
    return t;
}

// The guide finds the cell the plain search over the CDF finds, for every u (the same points,
// so the same images as before the guide), including u on and next to the CDF's entries.
TEST(PortalTable, GuidedCellIsThePlainSearchs) {
    EXPECT_EQ(etk::etk_guide_cells(ETK_PORTAL_CELLS), ETK_PORTAL_GUIDE_CELLS);
    for (double bright : {1.0, 200.0, 1e6}) {
        const std::vector<float> t = make_table(13u, bright);
        const float* cdf = t.data() + ETK_PORTAL_CDF;
        std::vector<float> us;
        std::mt19937 rng(5u);
        std::uniform_real_distribution<float> U(0.0f, 1.0f);
        for (int i = 0; i < 100000; ++i)
            us.push_back(std::min(U(rng), 0.99999994f));
        for (int k = 0; k < ETK_PORTAL_CELLS; k += 7)
            for (float u : {cdf[k], std::nextafter(cdf[k], 0.0f), std::nextafter(cdf[k], 1.0f)})
                us.push_back(std::min(u, 0.99999994f));
        for (float u : us)
            ASSERT_EQ(etk::etk_find_interval_guided(cdf, ETK_PORTAL_CELLS,
                                                    t.data() + ETK_PORTAL_GUIDE, u),
                      etk::etk_find_interval(cdf, ETK_PORTAL_CELLS, u))
                << "u = " << u << ", bright " << bright;
    }
}

// Points inside the box: the middle, 0.25 from a face, 0.007 from three faces (a corner).
std::vector<etk::float3> origins() {
    return {etk::make_float3(2.0f, 1.5f, 2.7f), etk::make_float3(4.75f, 1.0f, 3.0f),
            etk::make_float3(-0.999f, 0.001f, 3.499f)};
}

class PortalGuide : public ::testing::TestWithParam<int> {};

TEST_P(PortalGuide, SampledPointsLeaveByTheirCell) {
    const std::vector<float> t = make_table(11u, 200.0);
    const etk::float3 o = origins()[GetParam()];
    const int n = 1 << 20;
    std::mt19937 rng(77u + GetParam());
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<double> observed(ETK_PORTAL_CELLS, 0.0), expected(ETK_PORTAL_CELLS);
    int zero = 0;
    for (int k = 0; k < ETK_PORTAL_CELLS; ++k)
        expected[k] = double(n) * (t[ETK_PORTAL_CDF + k + 1] - t[ETK_PORTAL_CDF + k]);
    for (int i = 0; i < n; ++i) {
        const etk::float3 y = etk::etk_portal_point(
            t.data(), etk::make_float2(U(rng), std::min(U(rng), 0.99999994f)));
        const etk::float3 d = etk::normalize(y - o);
        float dist;
        const int k = etk::etk_portal_exit(t.data(), o, d, &dist);
        ASSERT_GE(k, 0);
        ASSERT_LT(k, ETK_PORTAL_CELLS);
        observed[k] += 1.0;
        zero += !(etk::etk_portal_pdf(t.data(), o, d) > 0.0f);
    }
    // A point within float rounding of a cell's edge can leave by the neighbour's (~2 in 10^5
    // here: the density the kernels use is the evaluated one, so MIS stays consistent); no more.
    EXPECT_LE(zero, n / 20000);
    const ett::Chi2Result chi = ett::chi2_test(observed, expected, ETK_PORTAL_N, 6 * ETK_PORTAL_N,
                                               ett::sidak_alpha(0.01, kTests), 5.0, n / 20000);
    EXPECT_TRUE(chi.passed) << chi.report;
}

INSTANTIATE_TEST_SUITE_P(Origins, PortalGuide, ::testing::Values(0, 1, 2));

// Next to a face the cells far along it are seen at grazing angles, each in a solid angle below
// the quadrature grid's: the integral is checked from the first two points only (the sampling
// test above covers the corner).
class PortalDensity : public ::testing::TestWithParam<int> {};

TEST_P(PortalDensity, IntegratesToOne) {
    // Cells 5x brighter, not 200x: a cell far away that holds most of the probability in a
    // small solid angle would need a finer grid than the test can afford.
    const std::vector<float> t = make_table(12u, 5.0);
    const etk::float3 o = origins()[GetParam()];
    // Midpoint rule over an equal-area grid: z uniform in [-1, 1], azimuth uniform.
    const int nz = 2048, nphi = 4096;
    double sum = 0.0;
    int zero = 0;
    for (int a = 0; a < nz; ++a) {
        const double z = -1.0 + (a + 0.5) * 2.0 / nz, r = std::sqrt(1.0 - z * z);
        for (int b = 0; b < nphi; ++b) {
            const double phi = (b + 0.5) * 2.0 * M_PI / nphi;
            const etk::float3 d =
                etk::make_float3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
            const float pdf = etk::etk_portal_pdf(t.data(), o, d);
            ASSERT_TRUE(std::isfinite(pdf) && pdf >= 0.0f);
            sum += pdf;
            float dist;
            const int k = etk::etk_portal_exit(t.data(), o, d, &dist);
            if (t[ETK_PORTAL_CDF + k + 1] == t[ETK_PORTAL_CDF + k]) {
                EXPECT_EQ(pdf, 0.0f);
                ++zero;
            }
        }
    }
    EXPECT_NEAR(sum * 4.0 * M_PI / (double(nz) * nphi), 1.0, 1e-3);
    EXPECT_GT(zero, 0); // the empty cells are seen, with density 0
}

INSTANTIATE_TEST_SUITE_P(Origins, PortalDensity, ::testing::Values(0, 1));

// The box holds the scene strictly inside, also for flat scenes and far from the origin.
TEST(PortalBox, EnclosesTheBoundsStrictly) {
    const float lo[3] = {1.0e4f, 0.0f, -3.0f}, hi[3] = {1.0e4f + 2.0f, 0.0f, 3.0f};
    const std::array<float, 6> box = et::guide_portal_box(lo, hi);
    for (int k = 0; k < 3; ++k) {
        EXPECT_LT(box[k], lo[k]);
        EXPECT_GT(box[3 + k], hi[k]);
    }
    // A point on the flat scene's plane leaves the box at a positive distance, every way.
    std::vector<float> t(etk::etk_portal_size(1), 0.0f);
    std::copy(box.begin(), box.end(), t.begin());
    for (int s = 0; s < 2; ++s) {
        float dist;
        etk::etk_portal_exit(t.data(), etk::make_float3(1.0e4f + 1.0f, 0.0f, 0.0f),
                             etk::make_float3(0.0f, s ? 1.0f : -1.0f, 0.0f), &dist);
        EXPECT_GT(dist, 0.0f);
    }
}

} // namespace
