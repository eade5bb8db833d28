// The continuation guide (kernels/continuation_guide.h): its equal-area regions of the sphere
// must map back to themselves, its density must integrate to one over the sphere, and the
// mixture the shade stage draws a guided continuation from (the cell's regions with probability
// c, else the BSDF) must draw directions with exactly the density it reports and that the MIS
// weights evaluate (chi-square over 32 x 64 equal-area bins of the sphere, expected counts
// integrated from the reported density), also when part of the guided share goes to the
// secondary-source table's points (a box around the vertex, its own density written out here).
#include "chi2.h"
#include "kernels/continuation_guide.h"
#include "load/env_distribution.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace {

constexpr int K = ETK_GUIDE_REGIONS;
constexpr int kTests = 3; // chi-square tests in this file, family-wise alpha 0.01

// One slot: the light sample's table (unused here), then the continuation guide's, random with
// some regions of zero probability; the portal table (unused) and the secondary-source table (off
// unless make_spots turns it on).
struct Cell {
    std::vector<float> floats = std::vector<float>(
        ETK_GUIDE_CELL_FLOATS + ETK_GUIDE_DIR_FLOATS + 2 * etk::etk_portal_size(1), 0.0f);
    std::vector<double> spot = std::vector<double>(ETK_PORTAL_CELLS, 0.0); // cell probabilities
    std::vector<double> P = std::vector<double>(K, 0.0);
    etk::EtkScene S{};
    etk::EtkParams p{};
};

void make(Cell& c, uint32_t seed, float share) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    double total = 0.0;
    for (int R = 0; R < K; ++R) {
        c.P[R] = R % 7 == 3 ? 0.0 : (R == 37 ? 20.0 : U(rng));
        total += c.P[R];
    }
    float* cdf = c.floats.data() + ETK_GUIDE_CELL_FLOATS;
    double run = 0.0;
    for (int R = 0; R < K; ++R) {
        c.P[R] /= total;
        run += c.P[R];
        cdf[R + 1] = static_cast<float>(run);
    }
    cdf[K] = 1.0f;
    for (int R = 0; R < K; ++R) // the density the table really holds
        c.P[R] = double(cdf[R + 1]) - double(cdf[R]);
    cdf[ETK_GUIDE_DIR_SHARE] = share;
    c.S.guide_cells = c.floats.data();
    c.p.guide_slots = 1;
    c.p.guide_continuation = 1;
}

// The secondary-source table on, with share q: a box of unequal sides, random probabilities per
// block of 8 x 8 cells (so that the quadrature of bin_mass sees few edges) with some zero, one
// face much brighter.
void make_spots(Cell& c, uint32_t seed, float q) {
    float* t =
        c.floats.data() + ETK_GUIDE_CELL_FLOATS + ETK_GUIDE_DIR_FLOATS + etk::etk_portal_size(1);
    const float box[6] = {-1.0f, -0.5f, -2.0f, 2.0f, 1.5f, 1.0f};
    std::copy(box, box + 6, t);
    t[ETK_PORTAL_ON] = 1.0f;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    double total = 0.0;
    constexpr int kB = ETK_PORTAL_N / 8; // blocks along a face's side
    std::vector<double> block(6 * kB * kB);
    for (size_t k = 0; k < block.size(); ++k)
        block[k] = k % 5 == 2 ? 0.0 : U(rng) * (k / (kB * kB) == 2 ? 30.0 : 1.0);
    for (int k = 0; k < ETK_PORTAL_CELLS; ++k) {
        const int face = k / (ETK_PORTAL_N * ETK_PORTAL_N),
                  rest = k % (ETK_PORTAL_N * ETK_PORTAL_N);
        const int i = rest / ETK_PORTAL_N, j = rest % ETK_PORTAL_N;
        c.spot[k] = block[(face * kB + i / 8) * kB + j / 8];
        total += c.spot[k];
    }
    double run = 0.0;
    t[ETK_PORTAL_CDF] = 0.0f;
    for (int k = 0; k < ETK_PORTAL_CELLS; ++k) {
        run += c.spot[k];
        t[ETK_PORTAL_CDF + k + 1] = static_cast<float>(run / total);
    }
    t[ETK_PORTAL_CDF + ETK_PORTAL_CELLS] = 1.0f;
    et::build_cdf_guide(t + ETK_PORTAL_CDF, ETK_PORTAL_CELLS, t + ETK_PORTAL_GUIDE);
    for (int k = 0; k < ETK_PORTAL_CELLS; ++k)
        c.spot[k] = double(t[ETK_PORTAL_CDF + k + 1]) - double(t[ETK_PORTAL_CDF + k]);
    t[ETK_PORTAL_SHARES] = q;
}

// The secondary-source table's density of unit direction d from o, written out independently
// of portal_guide.h: where the ray leaves the box, the cell's probability over its area, times
// t^2 / |cos| at the face.
double spot_pdf(const Cell& c, const double o[3], const double d[3]) {
    const double lo[3] = {-1.0, -0.5, -2.0}, hi[3] = {2.0, 1.5, 1.0};
    double t = 1e300;
    int axis = 0;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0)
            continue;
        const double ta = ((d[a] > 0.0 ? hi[a] : lo[a]) - o[a]) / d[a];
        if (ta < t) {
            t = ta;
            axis = a;
        }
    }
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const double f1 = (o[a1] + t * d[a1] - lo[a1]) / (hi[a1] - lo[a1]);
    const double f2 = (o[a2] + t * d[a2] - lo[a2]) / (hi[a2] - lo[a2]);
    const int i = std::clamp(static_cast<int>(f1 * ETK_PORTAL_N), 0, ETK_PORTAL_N - 1);
    const int j = std::clamp(static_cast<int>(f2 * ETK_PORTAL_N), 0, ETK_PORTAL_N - 1);
    const int face = 2 * axis + (d[axis] > 0.0 ? 1 : 0);
    const double area = (hi[a1] - lo[a1]) * (hi[a2] - lo[a2]) / double(ETK_PORTAL_N * ETK_PORTAL_N);
    return c.spot[(face * ETK_PORTAL_N + i) * ETK_PORTAL_N + j] / area * t * t / std::fabs(d[axis]);
}

// The vertex the mixture is drawn at: inside the box, wo in the shading frame.
etk::EtkSurface vertex(etk::float3 n, etk::float3 wo) {
    etk::EtkSurface s{};
    s.origin = s.origin_back = etk::make_float3(0.3f, 0.2f, -0.1f);
    s.ng = s.ns = n;
    s.wo = wo;
    return s;
}

TEST(ContinuationGuide, RegionsMapBackToThemselves) {
    for (int R = 0; R < K; ++R)
        for (int i = 0; i < 9; ++i)
            for (int j = 0; j < 9; ++j) {
                // 7 interior points and, within the polynomial atan2's few ulps, the edges.
                const float ti = i == 0 ? 1e-3f : i == 8 ? 0.999f : (i - 0.5f) / 7.0f;
                const float tj = j == 0 ? 1e-3f : j == 8 ? 0.999f : (j - 0.5f) / 7.0f;
                const etk::float2 t = etk::make_float2(ti, tj);
                const etk::float3 d = etk::etk_cguide_region_dir(R, t);
                ASSERT_NEAR(etk::dot(d, d), 1.0f, 1e-5f);
                ASSERT_EQ(etk::etk_cguide_region(d), R) << "t " << t.x << " " << t.y;
            }
    // The poles and the seam of the azimuth.
    EXPECT_EQ(etk::etk_cguide_region(etk::make_float3(0, 1, 0)) / ETK_GUIDE_COLS, 0);
    EXPECT_EQ(etk::etk_cguide_region(etk::make_float3(0, -1, 0)) / ETK_GUIDE_COLS,
              ETK_GUIDE_ROWS - 1);
    EXPECT_EQ(etk::etk_cguide_region(etk::normalize(etk::make_float3(1e-4f, 0, 1))) %
                  ETK_GUIDE_COLS,
              ETK_GUIDE_COLS - 1);
    EXPECT_EQ(
        etk::etk_cguide_region(etk::normalize(etk::make_float3(-1e-4f, 0, 1))) % ETK_GUIDE_COLS, 0);
}

// The guide's density over a fine equal-area grid of the sphere sums to one (each grid cell
// lies inside one region), and is the table's probability over the region's solid angle.
TEST(ContinuationGuide, DensityIntegratesToOne) {
    Cell c;
    make(c, 5u, 0.5f);
    const int ny = 256, nphi = 512;
    double sum = 0.0;
    for (int i = 0; i < ny; ++i)
        for (int j = 0; j < nphi; ++j) {
            const float y = 1.0f - 2.0f * (i + 0.5f) / ny;
            const float phi = -float(M_PI) + 2.0f * float(M_PI) * (j + 0.5f) / nphi;
            const float r = std::sqrt(1.0f - y * y);
            const etk::float3 d = etk::make_float3(r * std::cos(phi), y, r * std::sin(phi));
            const double pdf = etk::etk_cguide_pdf(c.S, c.p, 0, d);
            const int R = etk::etk_cguide_region(d);
            ASSERT_NEAR(pdf, c.P[R] * K / (4.0 * M_PI), 1e-5 * (1.0 + pdf));
            sum += pdf * 4.0 * M_PI / (double(ny) * nphi);
        }
    EXPECT_NEAR(sum, 1.0, 1e-5);
}

// The density of the mixture of share c at a vertex of normal n (world), integrated over the
// bin (i, j) of a ny x nphi equal-area grid (bands of y, sectors of longitude) by a sub x sub
// midpoint rule.
double bin_mass(const Cell& cell, float c, const etk::EtkMaterial& m, etk::float3 wo_local,
                etk::float3 t, etk::float3 b, etk::float3 n, int i, int j, int ny, int nphi,
                int sub) {
    double mass = 0.0;
    for (int a = 0; a < sub; ++a)
        for (int e = 0; e < sub; ++e) {
            const double y = 1.0 - 2.0 * (i + (a + 0.5) / sub) / ny;
            // Longitude u of the bin (latlong.h): the direction at angle a = pi (2u - 1).
            const double a_u = M_PI * (2.0 * (j + (e + 0.5) / sub) / nphi - 1.0);
            const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
            const etk::float3 d =
                etk::make_float3(static_cast<float>(r * std::sin(a_u)), static_cast<float>(y),
                                 static_cast<float>(-r * std::cos(a_u)));
            const etk::float3 wi = etk::etk_to_local(d, t, b, n);
            mass +=
                etk::etk_cguide_mix_pdf(cell.S, cell.p, 0, c, etk::etk_bsdf_pdf(m, wo_local, wi),
                                        vertex(n, wo_local).origin, d);
        }
    return mass * 4.0 * M_PI / (double(ny) * nphi * sub * sub);
}

struct MixCase {
    float share;
    float nx, ny, nz; // the vertex's normal (world, normalised below)
    float spots;      // the secondary-source table's share q (0: off)
};

class ContinuationMixture : public ::testing::TestWithParam<MixCase> {};

TEST_P(ContinuationMixture, SamplesMatchTheirDensity) {
    const MixCase mc = GetParam();
    Cell cell;
    make(cell, 11u, mc.share);
    if (mc.spots > 0.0f)
        make_spots(cell, 23u, mc.spots);
    etk::EtkMaterial m{};
    m.type = ETK_MAT_DIFFUSE;
    m.albedo = etk::make_float3(0.8f, 0.6f, 0.4f);
    const etk::float3 n = etk::normalize(etk::make_float3(mc.nx, mc.ny, mc.nz));
    etk::float3 t, b;
    etk::etk_make_frame(n, &t, &b);
    const etk::float3 wo = etk::normalize(etk::make_float3(0.3f, -0.2f, 0.9f)); // local
    const int ny = 32, nphi = 64, n_samples = 1 << 20;
    std::vector<double> observed(ny * nphi, 0.0), expected(ny * nphi, 0.0);
    std::mt19937 rng(77u);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    int mismatched = 0, lost = 0;
    for (int k = 0; k < n_samples; ++k) {
        const etk::float2 u =
            etk::make_float2(std::min(U(rng), 0.99999994f), std::min(U(rng), 0.99999994f));
        const etk::EtkGuidedSample g = etk::etk_cguide_sample_mixture(
            cell.S, cell.p, 0, mc.share, m, vertex(n, wo), t, b, n, u, U(rng));
        if (!(g.pdf > 0.0f)) {
            ++lost;
            continue;
        }
        // The density reported, against one written out here: c ((1 - q) P(R) K / 4 pi + q p_spot)
        // + (1 - c) cos / pi, R from the direction's y band and longitude (latlong.h: u = (1 +
        // atan2(x, -z) / pi) / 2).
        const etk::float3 d = g.wi_world;
        const double lon = 0.5 * (1.0 + std::atan2(double(d.x), -double(d.z)) / M_PI);
        const int band =
            std::min(ETK_GUIDE_ROWS - 1, static_cast<int>((1.0 - d.y) * 0.5 * ETK_GUIDE_ROWS));
        const int col = std::min(ETK_GUIDE_COLS - 1, static_cast<int>(lon * ETK_GUIDE_COLS));
        const double cos_n = etk::dot(d, n);
        const double o[3] = {0.3, 0.2, -0.1}, dd[3] = {d.x, d.y, d.z};
        const double guide = cell.P[band * ETK_GUIDE_COLS + col] * K / (4.0 * M_PI);
        const double expect =
            mc.share * ((1.0 - mc.spots) * guide +
                        (mc.spots > 0.0f ? mc.spots * spot_pdf(cell, o, dd) : 0.0)) +
            (1.0 - mc.share) * std::max(0.0, cos_n) / M_PI;
        mismatched += std::fabs(expect - g.pdf) > 1e-4 * expect;
        const int i = std::min(ny - 1, static_cast<int>((1.0f - d.y) * 0.5f * ny));
        const int j = std::min(nphi - 1, static_cast<int>(lon * nphi));
        observed[i * nphi + j] += 1.0;
    }
    // A sampled direction's region is found again from its float coordinates through the
    // polynomial atan2 (a few ulps): within that of a region's edge it can land in the
    // neighbour, whose probability the density then reports (about 5 samples in 10^6 here; a
    // bias far below float noise). More than 2e-5 of the samples would be a real mismatch.
    EXPECT_EQ(lost, 0);
    EXPECT_LE(mismatched, n_samples / 50000);
    double total = 0.0;
    for (int i = 0; i < ny; ++i)
        for (int j = 0; j < nphi; ++j) {
            // Finer quadrature where the spot table's block edges cross the bins.
            const double mass =
                bin_mass(cell, mc.share, m, wo, t, b, n, i, j, ny, nphi, mc.spots > 0.0f ? 32 : 12);
            expected[i * nphi + j] = n_samples * mass;
            total += mass;
        }
    EXPECT_NEAR(total, 1.0, 2e-3) << "the mixture's density does not integrate to one";
    const ett::Chi2Result chi =
        ett::chi2_test(observed, expected, nphi, ny, ett::sidak_alpha(0.01, kTests), 5.0,
                       n_samples / 50000.0); // the same edge slivers, into zero-probability regions
    EXPECT_TRUE(chi.passed) << chi.report;
}

// Half guided, normal up (the horizon on a bin boundary); mostly guided, a tilted normal; and
// with half the guided share to the secondary-source table's points.
INSTANTIATE_TEST_SUITE_P(Shares, ContinuationMixture,
                         ::testing::Values(MixCase{0.5f, 0.0f, 1.0f, 0.0f, 0.0f},
                                           MixCase{0.8f, 0.4f, 0.7f, -0.5f, 0.0f},
                                           MixCase{0.5f, 0.4f, 0.7f, -0.5f, 0.5f}));

// Only diffuse vertices guide, only when the option is on, with the cell's share.
TEST(ContinuationGuide, ShareOnlyAtDiffuseVerticesWithTheOptionOn) {
    Cell c;
    make(c, 3u, 0.375f);
    etk::EtkParams p = c.p;
    etk::EtkMaterial m{};
    m.type = ETK_MAT_DIFFUSE;
    EXPECT_EQ(etk::etk_cguide_share(c.S, p, 0, m), 0.375f);
    m.type = ETK_MAT_MICROFACET;
    EXPECT_EQ(etk::etk_cguide_share(c.S, p, 0, m), 0.0f);
    m.type = ETK_MAT_DIFFUSE;
    p.guide_continuation = 0;
    EXPECT_EQ(etk::etk_cguide_share(c.S, p, 0, m), 0.0f);
    // Share 0: the mixture is the BSDF's density.
    const etk::float3 d = etk::make_float3(0.0f, 1.0f, 0.0f);
    EXPECT_EQ(etk::etk_cguide_mix_pdf(c.S, c.p, 0, 0.0f, 0.25f, d, d), 0.25f);
    // The secondary-source table's share: 0 while the table is off, its entry once it is on.
    EXPECT_EQ(etk::etk_spot_share(c.S, c.p, 0), 0.0f);
    make_spots(c, 1u, 0.25f);
    EXPECT_EQ(etk::etk_spot_share(c.S, c.p, 0), 0.25f);
}

} // namespace
