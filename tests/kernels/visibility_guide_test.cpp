// The visibility strategy's light sampling (kernels/visibility_guide.h): the mixture of the map's
// distribution and a cell's learned table over regions, each region sampled in proportion to the
// map, must draw directions with exactly the density it reports (chi-square over the map's
// distribution cells, where both are piecewise constant in the lat-long square, so expected
// counts are exact), that density must integrate to one (and E[1 / pdf] over the sphere must be
// its area: no direction the map lights is missed), and the learned tables must not depend on
// the order records arrive in (host/lib/render/visibility_cache.h).
#include "chi2.h"
#include "guide_sampling_check.h"
#include "kernels/continuation_guide.h"
#include "kernels/portal_guide.h"
#include "kernels/visibility_guide.h"
#include "load/env_distribution.h"
#include "render/visibility_cache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <utility>
#include <vector>

namespace {

constexpr int K = ETK_GUIDE_REGIONS;
constexpr int kTests = 4; // chi-square tests in this file, family-wise alpha 0.01

struct Fixture {
    et::EnvDistribution dist;
    std::vector<float> regions, cells;
    etk::EtkScene S{};
    etk::EtkParams p{};
};

// A w x h map of random positive radiance with a bright spot, its distribution, the region
// tables and one cell whose table is random (with some regions at zero). black_band: the map's
// second row band of regions is black (so are its Q, as the host's tables would be: no light
// sample lands there, so no record does).
void make(Fixture& f, int w, int h, uint32_t seed, bool black_band = false) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.05f, 1.0f);
    et::RgbImage img;
    img.width = w;
    img.height = h;
    img.rgb.resize(static_cast<size_t>(w) * h * 3);
    for (float& x : img.rgb)
        x = U(rng);
    for (int k = 0; k < 3; ++k) // a sun
        img.rgb[3 * (static_cast<size_t>(h / 3) * w + w / 5) + k] = 500.0f;
    if (black_band)
        for (int r = etk::etk_guide_row_start(1, h); r < etk::etk_guide_row_start(2, h); ++r)
            std::fill_n(img.rgb.begin() + 3 * static_cast<size_t>(r) * w, 3 * w, 0.0f);
    et::DistributionOptions o;
    o.threads = 1;
    f.dist = et::build_env_distribution(img, o);
    f.regions = et::guide_region_tables(f.dist.table, w, h);
    // A learned table P (some regions at zero, whole row bands among them), mixed with the
    // map's region masses M as the host does: Q = alpha M + (1 - alpha) P, alpha = 1/4.
    std::vector<double> prob(K);
    for (int R = 0; R < K; ++R)
        prob[R] = (R % 5 == 0 || R / ETK_GUIDE_COLS == 2 || (black_band && R / ETK_GUIDE_COLS == 1))
                      ? 0.0
                      : std::pow(double(U(rng)), 4.0);
    double total = 0.0;
    for (double x : prob)
        total += x;
    f.cells.assign(K + 1, 0.0f);
    double run = 0.0;
    for (int R = 0; R < K; ++R) {
        run += 0.25 * f.regions[R] + 0.75 * prob[R] / total;
        f.cells[R + 1] = static_cast<float>(run);
    }
    f.cells[K] = 1.0f;
    f.S.env_dist = f.dist.table.data();
    f.S.guide_regions = f.regions.data();
    f.S.guide_cells = f.cells.data();
    f.p.env.tex_w = f.p.env.dist_w = w;
    f.p.env.tex_h = f.p.env.dist_h = h;
    f.p.env.scale = 1.0f;
    f.p.env.rot_cos = 1.0f;
    f.p.env.has_light = 1;
    f.p.guide_slots = 1;
    f.p.guide_ready = 1;
}

class VisibilityGuide : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(VisibilityGuide, SamplesMatchTheirDensity) {
    const auto [w, h] = GetParam();
    Fixture f;
    make(f, w, h, 7u + w);
    const ett::GuideSamplingCheck g =
        ett::check_guide_sampling(f.S, f.p, 0, 1 << 20, 2024u + w, ett::sidak_alpha(0.01, kTests));
    EXPECT_EQ(g.bad, 0);
    EXPECT_EQ(g.mismatched, 0);
    EXPECT_NEAR(g.integral, 1.0, 1e-4) << "the mixture's density does not integrate to one";
    EXPECT_TRUE(g.chi.passed) << g.chi.report;
    // E[1 / pdf] = the sphere's area where the density is positive everywhere (this map).
    EXPECT_NEAR(g.mean_inv_pdf, 4.0 * M_PI, 5.0 * g.sd_inv_pdf) << "sd " << g.sd_inv_pdf;
}

// The light sample with learned portals (kernels/portal_guide.h): the mixture of the cell's
// distribution and the portal table, from a surface point inside the box. The density it
// reports is the one the escaped stage evaluates for MIS (from the origin on the direction's
// side), E[1 / pdf] is the sphere's area and E[g / pdf] the integral of a smooth g: nothing is
// drawn more or less often than reported. And with the portal share 0 the sample is the cell's
// own, bit for bit.
TEST_P(VisibilityGuide, PortalMixtureIsUnbiased) {
    const auto [w, h] = GetParam();
    Fixture f;
    make(f, w, h, 9u + w);
    // The portal table after the cell's: a box around the point, light through one face's
    // middle cells (a window) and a few others.
    const float lo[3] = {0.0f, 0.0f, 0.0f}, hi[3] = {4.0f, 3.0f, 5.0f};
    const std::array<float, 6> box = et::guide_portal_box(lo, hi);
    f.cells.resize(ETK_GUIDE_CELL_FLOATS + etk::etk_portal_size(1), 0.0f);
    float* t = f.cells.data() + etk::etk_portal_offset(1, 0);
    std::copy(box.begin(), box.end(), t);
    t[ETK_PORTAL_ON] = 1.0f;
    std::vector<double> wt(ETK_PORTAL_CELLS, 0.0);
    for (int i = 12; i < 20; ++i)
        for (int j = 10; j < 16; ++j)
            wt[(4 * ETK_PORTAL_N + i) * ETK_PORTAL_N + j] = 1.0; // face -z
    wt[7] = wt[3000] = 5.0;
    double run = 0.0;
    for (int k = 0; k < ETK_PORTAL_CELLS; ++k) {
        run += wt[k] / 50.0;
        t[ETK_PORTAL_CDF + k + 1] = static_cast<float>(run);
    }
    et::build_cdf_guide(t + ETK_PORTAL_CDF, ETK_PORTAL_CELLS, t + ETK_PORTAL_GUIDE);
    f.S.guide_cells = f.cells.data();
    etk::EtkSurface s{};
    s.ng = etk::make_float3(0.0f, 1.0f, 0.0f);
    s.origin = etk::make_float3(1.0f, 0.5f + 1e-4f, 3.0f);
    s.origin_back = etk::make_float3(1.0f, 0.5f - 1e-4f, 3.0f);
    const int n = 1 << 20;
    std::mt19937 rng(4048u + w);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    for (float b : {0.0f, 0.5f}) {
        t[ETK_PORTAL_SHARES] = b;
        double inv = 0.0, inv2 = 0.0, g = 0.0, g2 = 0.0;
        int mismatched = 0, portal = 0, same = 0;
        for (int i = 0; i < n; ++i) {
            const etk::float2 u =
                etk::make_float2(std::min(U(rng), 0.99999994f), std::min(U(rng), 0.99999994f));
            etk::float2 parts;
            const etk::EtkEnvSample r = etk::etk_guide_light_sample(f.S, f.p, 0, s, u, &parts);
            ASSERT_TRUE(r.pdf > 0.0f && std::isfinite(r.pdf));
            const float again = etk::etk_guide_light_pdf(
                f.S, f.p, 0, etk::etk_surface_origin(s, r.dir), r.dir, r.uv);
            mismatched += std::fabs(again - r.pdf) > 1e-4f * r.pdf;
            portal += u.x < b;
            if (b == 0.0f) {
                const etk::EtkEnvSample c = etk::etk_guide_sample(f.S, f.p, 0, u);
                same += c.pdf == r.pdf && c.uv.x == r.uv.x && c.uv.y == r.uv.y;
            }
            const double x = 1.0 / r.pdf, y = (1.0 + r.dir.x) * (1.0 + r.dir.x) / r.pdf;
            inv += x;
            inv2 += x * x;
            g += y;
            g2 += y * y;
        }
        // The vis part's density comes from the sample's own sin theta, the evaluation's from
        // uv: a few in 10^5 differ beyond 1e-4 (as etk_env_sample's do).
        EXPECT_LE(mismatched, n / 10000) << "share " << b;
        if (b == 0.0f)
            EXPECT_EQ(same, n);
        else
            EXPECT_GT(portal, n / 3);
        const double mi = inv / n, sdi = std::sqrt((inv2 / n - mi * mi) / n);
        const double mg = g / n, sdg = std::sqrt((g2 / n - mg * mg) / n);
        EXPECT_NEAR(mi, 4.0 * M_PI, 5.0 * sdi) << "share " << b;
        EXPECT_NEAR(mg, 16.0 * M_PI / 3.0, 5.0 * sdg) << "share " << b; // (1 + x)^2 over S^2
    }
}

// 64 x 32: regions of 4 x 4 cells; 50 x 27: regions of unequal sizes (floor boundaries).
INSTANTIATE_TEST_SUITE_P(Sizes, VisibilityGuide,
                         ::testing::Values(std::make_pair(64, 32), std::make_pair(50, 27)));

// The warp is an inversion, as the paper's: for a fixed u.y, uv.x never decreases as u.x grows
// (the column of regions, then of the map inside the region, follow u.x in order), and a regular
// n x n grid of points puts into each region its probability's share n^2 Q(R) up to the
// rounding of the grid -- within n (the row band's rows of points) + n B (B the band's mass, one
// point per row) + 2. A region or technique chosen by a separate random number would miss
// both: the stratification of the Sobol' points is what the hierarchy keeps. Also with a black
// band of regions (probability zero), which the inversion must step over.
class VisibilityWarp : public ::testing::TestWithParam<bool> {};

TEST_P(VisibilityWarp, IsAnInversion) {
    Fixture f;
    make(f, 64, 32, 11u, GetParam());
    const int n = 256;
    std::vector<double> count(K, 0.0);
    int decreasing = 0;
    for (int j = 0; j < n; ++j) {
        float last = -1.0f;
        for (int i = 0; i < n; ++i) {
            const etk::float2 u = etk::make_float2((i + 0.5f) / n, (j + 0.5f) / n);
            const etk::EtkEnvSample s = etk::etk_guide_sample(f.S, f.p, 0, u);
            ASSERT_GT(s.pdf, 0.0f);
            count[etk::etk_guide_region(f.p.env, s.uv)] += 1.0;
            decreasing += s.uv.x < last;
            last = s.uv.x;
        }
    }
    EXPECT_EQ(decreasing, 0);
    for (int R = 0; R < K; ++R) {
        const int band = R / ETK_GUIDE_COLS;
        const double Q = double(f.cells[R + 1]) - f.cells[R];
        const double B =
            double(f.cells[(band + 1) * ETK_GUIDE_COLS]) - f.cells[band * ETK_GUIDE_COLS];
        EXPECT_NEAR(count[R], double(n) * n * Q, n + n * B + 2.0) << "region " << R;
        if (Q == 0.0) {
            EXPECT_EQ(count[R], 0.0) << "region " << R << " has probability zero";
        }
    }
}

INSTANTIATE_TEST_SUITE_P(BlackBand, VisibilityWarp, ::testing::Values(false, true));

// A guided sample finds its column from the region tables' copies of the CDF at the sub-band
// starts and then the sub-band's own entries (etk_guide_column): it must be the column the plain
// search over the whole row gives, clamped to the band, for every x a sample can produce (x in
// [CDF at the band's start, at its end]: every CDF entry of the band and its float neighbours,
// a grid, the ends). Maps wider than the sub-bands, of unequal sub-bands, narrower than the
// column bands (bands and sub-bands of no columns) and with black rows (flat CDFs, ties).
class VisibilityColumn : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(VisibilityColumn, EqualsThePlainSearchInItsBand) {
    const auto [w, h] = GetParam();
    Fixture f;
    make(f, w, h, 13u + w, true);
    const float* ccdf0 = f.dist.table.data() + etk::etk_dist2d_conditional_cdf(w, h);
    long checked = 0;
    for (int r = 0; r < h; ++r) {
        const float* ccdf = ccdf0 + static_cast<size_t>(r) * (w + 1);
        const float* split = f.regions.data() + etk::etk_guide_split_table(r, h);
        for (int Rc = 0; Rc < ETK_GUIDE_COLS; ++Rc) {
            const int c0 = etk::etk_guide_col_start(Rc, w),
                      c1 = etk::etk_guide_col_start(Rc + 1, w);
            if (c0 == c1)
                continue; // a band of no columns: zero mass, never sampled
            const float a = ccdf[c0], b = ccdf[c1];
            std::vector<float> xs;
            for (int c = c0; c <= c1; ++c)
                for (float x :
                     {ccdf[c], std::nextafter(ccdf[c], 0.0f), std::nextafter(ccdf[c], 2.0f)})
                    xs.push_back(x);
            for (int k = 0; k <= 64; ++k)
                xs.push_back(a + std::min(k / 64.0f, 0.99999994f) * (b - a));
            for (float x : xs) {
                if (x < a || x > b)
                    continue;
                const int plain = std::clamp(etk::etk_find_interval(ccdf, w, x), c0, c1 - 1);
                ASSERT_EQ(etk::etk_guide_column(ccdf, split, Rc, w, x), plain)
                    << "row " << r << " band " << Rc << " x " << x;
                ++checked;
            }
        }
    }
    EXPECT_GT(checked, 3L * w * h);
}

INSTANTIATE_TEST_SUITE_P(Sizes, VisibilityColumn,
                         ::testing::Values(std::make_pair(1024, 64), std::make_pair(64, 32),
                                           std::make_pair(50, 27), std::make_pair(7, 9),
                                           std::make_pair(100, 3)));

// Before anything is learned the strategy is the paper's map sampling.
TEST(VisibilityGuideTables, PriorIsTheMap) {
    Fixture f;
    make(f, 64, 32, 3u);
    const float lo[3] = {0.0f, 0.0f, 0.0f}, hi[3] = {1.0f, 1.0f, 1.0f};
    f.cells = et::guide_prior_cells(f.regions, 1, false, et::guide_portal_box(lo, hi));
    f.S.guide_cells = f.cells.data();
    for (int r = 0; r < 32; ++r)
        for (int c = 0; c < 64; ++c) {
            const etk::float2 uv = etk::make_float2((c + 0.5f) / 64.0f, (r + 0.5f) / 32.0f);
            // Q(R) is a difference of two float CDF entries (each within 2^-24 of its double):
            // relative to the region's mass M_R that is up to 1.2e-7 / M_R; twice that, plus
            // float rounding of the factor itself.
            const double M = f.regions[etk::etk_guide_region(f.p.env, uv)];
            EXPECT_NEAR(etk::etk_guide_factor(f.S, f.p, 0, uv), 1.0, 1e-6 + 2.4e-7 / M);
        }
}

// Options of 64 slots with continuation records, and a box of 4 x 1 x 0.5 for their portal
// tables.
et::VisibilityOptions sixty_four_slots() {
    et::VisibilityOptions o;
    o.slots = 64;
    o.continuation = true;
    return o;
}
const float kSlabLo[3] = {-1.0f, 0.0f, 2.0f}, kSlabHi[3] = {3.0f, 1.0f, 2.5f};
std::array<float, 6> slab_box() {
    return et::guide_portal_box(kSlabLo, kSlabHi);
}
// A cache of those over a 64 x 32 map (f).
std::unique_ptr<et::VisibilityCache> slab_cache(Fixture& f) {
    make(f, 64, 32, 5u);
    return std::make_unique<et::VisibilityCache>(sixty_four_slots(), f.regions, 3.0, slab_box());
}

// absorb() leaves every word of the device's sums zero -- the passes after an update add to
// them in place (the native device, and OpenCL where it maps them): a word it missed would be
// counted again at the next update.
TEST(VisibilityGuideTables, AbsorbLeavesTheSumsZero) {
    Fixture f;
    const auto cache = slab_cache(f);
    const et::VisibilityOptions o = sixty_four_slots();
    std::vector<uint32_t> sums(static_cast<size_t>(etk::etk_gsum_words(o.slots, 1)), 0u);
    std::mt19937 rng(3u);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    for (int ready : {0, 1}) { // the guided share's moments count only once the tables learned
        etk::EtkParams p{};
        p.guide_slots = o.slots;
        p.guide_inv_power = 0.5f;
        p.guide_continuation = 1;
        p.guide_continuation_share = 0.5f;
        p.guide_ready = ready;
        const std::vector<float>& cells = cache->tables();
        const float* portal = cells.data() + etk::etk_portal_offset(o.slots, 1);
        for (int i = 0; i < 4000; ++i) {
            const int key = static_cast<int>(rng() % (o.slots * K));
            const float value = 10.0f * U(rng);
            etk::etk_guide_record_light(sums.data(), p, portal, key, value, value,
                                        int(rng() % ETK_PORTAL_CELLS),
                                        etk::make_float2(0.1f + U(rng), U(rng)));
            const etk::float3 d =
                etk::normalize(etk::make_float3(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f));
            const int dkey = (key / K) * K + etk::etk_cguide_region(d);
            etk::etk_guide_record_continuation(sums.data(), p, cells.data(), dkey, 10.0f * U(rng),
                                               etk::make_float3(kSlabLo[0] + 4.0f * U(rng),
                                                                kSlabLo[1] + U(rng),
                                                                kSlabLo[2] + 0.5f * U(rng)),
                                               d, 0.05f + U(rng));
        }
        ASSERT_GT(std::count_if(sums.begin(), sums.end(), [](uint32_t w) { return w != 0u; }), 0);
        cache->absorb(sums.data(), sums.size());
        for (size_t k = 0; k < sums.size(); ++k)
            ASSERT_EQ(sums[k], 0u) << "ready " << ready << ", word " << k;
    }
    EXPECT_EQ(cache->records(), 8000u);
    EXPECT_EQ(cache->continuation_records(), 8000u);
}

// The share of the light the shadow rays found unblocked (the verdict's screen): the records'
// values over what they would have brought unblocked, however the rays were drawn; records
// outside the table carry nothing to it, and a cache that saw no light says so (-1).
TEST(VisibilityGuideTables, SeenShareIsTheUnblockedLightsShare) {
    Fixture f;
    const auto cache = slab_cache(f);
    EXPECT_EQ(cache->light_seen_share(), -1.0);
    const et::VisibilityOptions o = sixty_four_slots();
    std::mt19937 rng(4u);
    std::vector<int> keys, exits;
    std::vector<float> values, reaches, parts;
    double seen = 0.0, reach = 0.0;
    for (int i = 0; i < 3000; ++i) {
        const bool outside = i % 50 == 0, blocked = rng() % 4 == 0;
        const float v = std::ldexp(float(rng() % 1000 + 1), -10); // exact in the fixed point
        keys.push_back(outside ? -1 : static_cast<int>(rng() % (o.slots * K)));
        values.push_back(blocked ? 0.0f : v);
        reaches.push_back(v);
        exits.push_back(-1);
        parts.insert(parts.end(), {std::ldexp(float(rng() % 100 + 1), -6), 0.0f});
        seen += outside || blocked ? 0.0 : v;
        reach += outside ? 0.0 : v;
    }
    cache->add(keys.data(), values.data(), exits.data(), parts.data(), int(keys.size()),
               reaches.data());
    cache->tables();
    EXPECT_NEAR(cache->light_seen_share(), seen / reach, 1e-6); // (fixed point, relative to 3)
    EXPECT_GT(seen / reach, 0.7);
    EXPECT_LT(seen / reach, 0.8);
}

// The sums are fixed point: any order of the same records gives the same tables, bit for bit
// -- the light sample's and the continuation guide's (continuation_guide.h).
TEST(VisibilityGuideTables, IndependentOfRecordOrder) {
    Fixture f;
    make(f, 64, 32, 5u);
    et::VisibilityOptions o;
    o.slots = 64;
    std::mt19937 rng(9u);
    // Records of both kinds; continuation records only in the first half of the slots, and the
    // last of those with values 0 only (no light came back).
    std::vector<int> keys(5000), dkeys(3000);
    std::vector<float> values(5000), dvalues(3000);
    for (size_t i = 0; i < keys.size(); ++i) {
        keys[i] = static_cast<int>(rng() % (o.slots * K));
        values[i] = (rng() % 3 == 0) ? 0.0f : std::ldexp(float(rng() % 1000 + 1), -int(rng() % 20));
    }
    // Where the unoccluded ones left the box (some not at all), and their densities p_vis,
    // p_portal (the portal table's sums and the portal shares' second moments).
    std::vector<int> exits(keys.size());
    std::vector<float> parts(2 * keys.size());
    for (size_t i = 0; i < keys.size(); ++i) {
        exits[i] = values[i] > 0.0f && rng() % 4 != 0 ? int(rng() % ETK_PORTAL_CELLS) : -1;
        parts[2 * i] = std::ldexp(float(rng() % 1000 + 1), -int(rng() % 12));
        parts[2 * i + 1] =
            rng() % 5 == 0 ? 0.0f : std::ldexp(float(rng() % 1000 + 1), -int(rng() % 12));
    }
    const int dark = o.slots / 2 - 1;
    std::vector<int> dcount(o.slots, 0);
    for (size_t i = 0; i < dkeys.size(); ++i) {
        dkeys[i] = static_cast<int>(rng() % (o.slots / 2 * K));
        dvalues[i] = (rng() % 3 == 0 || dkeys[i] / K == dark)
                         ? 0.0f
                         : std::ldexp(float(rng() % 1000 + 1), -int(rng() % 20));
        ++dcount[dkeys[i] / K];
    }
    const float lo[3] = {-1.0f, 0.0f, 2.0f}, hi[3] = {3.0f, 1.0f, 2.5f};
    const std::array<float, 6> box = et::guide_portal_box(lo, hi);
    // The continuations' rays (origin in the box, 0, unit direction, density): the
    // secondary-source table's records and its shares' second moments.
    std::vector<float> drays(8 * dkeys.size());
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    for (size_t i = 0; i < dkeys.size(); ++i) {
        float* r = &drays[8 * i];
        for (int k = 0; k < 3; ++k)
            r[k] = lo[k] + (hi[k] - lo[k]) * U(rng);
        etk::float3 d =
            etk::normalize(etk::make_float3(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f));
        r[4] = d.x;
        r[5] = d.y;
        r[6] = d.z;
        r[7] = std::ldexp(float(rng() % 1000 + 1), -int(rng() % 12));
    }
    et::VisibilityCache a(o, f.regions, 3.0, box), b(o, f.regions, 3.0, box);
    a.add(keys.data(), values.data(), exits.data(), parts.data(), static_cast<int>(keys.size()));
    a.add_continuations(dkeys.data(), dvalues.data(), drays.data(), static_cast<int>(dkeys.size()));
    // The same records into b, shuffled, in uneven batches, the two kinds interleaved.
    auto batches = [&](const std::vector<int>& kk0, const std::vector<float>& vv0, bool dir,
                       size_t first, size_t step) {
        std::vector<size_t> order(kk0.size());
        for (size_t i = 0; i < order.size(); ++i)
            order[i] = i;
        std::shuffle(order.begin(), order.end(), rng);
        for (size_t k = first; k < order.size(); k += step) {
            std::vector<int> kk, ee;
            std::vector<float> vv, pp, rr;
            for (size_t j = k; j < std::min(order.size(), k + step); ++j) {
                kk.push_back(kk0[order[j]]);
                vv.push_back(vv0[order[j]]);
                if (dir)
                    rr.insert(rr.end(), &drays[8 * order[j]], &drays[8 * order[j]] + 8);
                else {
                    ee.push_back(exits[order[j]]);
                    pp.push_back(parts[2 * order[j]]);
                    pp.push_back(parts[2 * order[j] + 1]);
                }
            }
            if (dir)
                b.add_continuations(kk.data(), vv.data(), rr.data(), static_cast<int>(kk.size()));
            else
                b.add(kk.data(), vv.data(), ee.data(), pp.data(), static_cast<int>(kk.size()));
        }
    };
    batches(dkeys, dvalues, true, 0, 41);
    batches(keys, values, false, 0, 37);
    // Twice: the second update also depends on the portal shares the first chose.
    std::vector<float> ta = a.tables(), tb = b.tables();
    ASSERT_EQ(ta.size(), tb.size());
    EXPECT_TRUE(ta == tb);
    a.add(keys.data(), values.data(), exits.data(), parts.data(), static_cast<int>(keys.size()));
    batches(keys, values, false, 0, 53);
    a.add_continuations(dkeys.data(), dvalues.data(), drays.data(), static_cast<int>(dkeys.size()));
    batches(dkeys, dvalues, true, 0, 29);
    ta = a.tables();
    tb = b.tables();
    ASSERT_EQ(ta.size(), et::guide_cells_size(o.slots, true));
    ASSERT_EQ(ta.size(), static_cast<size_t>(o.slots) * (2 * K + 4) +
                             2 * static_cast<size_t>(etk::etk_portal_size(o.slots)));
    ASSERT_EQ(ta.size(), tb.size());
    EXPECT_TRUE(ta == tb);
    // Some cells chose portals, some not.
    const float* shares = ta.data() + etk::etk_portal_offset(o.slots, 1) + ETK_PORTAL_SHARES;
    EXPECT_GT(std::count(shares, shares + o.slots, 0.0f), 0);
    EXPECT_LT(std::count(shares, shares + o.slots, 0.0f), o.slots);
    // The secondary-source table is on, a CDF over the box's cells, with a share per slot from
    // the candidates (0 where a slot had no continuation records).
    {
        etk::EtkScene S{};
        S.guide_cells = ta.data();
        etk::EtkParams p{};
        p.guide_slots = o.slots;
        p.guide_continuation = 1;
        const float* spot = etk::etk_spot_table(S, p);
        EXPECT_EQ(spot[ETK_PORTAL_ON], 1.0f);
        EXPECT_EQ(spot[ETK_PORTAL_CDF], 0.0f);
        EXPECT_EQ(spot[ETK_PORTAL_CDF + ETK_PORTAL_CELLS], 1.0f);
        for (int k = 0; k < ETK_PORTAL_CELLS; ++k)
            ASSERT_LE(spot[ETK_PORTAL_CDF + k], spot[ETK_PORTAL_CDF + k + 1]);
        for (int s = 0; s < o.slots; ++s) {
            const float q = etk::etk_spot_share(S, p, s);
            bool candidate = false;
            for (int j = 0; j < ETK_PORTAL_CANDIDATES; ++j)
                candidate = candidate || q == etk::etk_portal_candidate(j);
            EXPECT_TRUE(candidate) << "slot " << s << ": " << q;
            if (dcount[s] == 0) {
                EXPECT_EQ(q, 0.0f) << "slot " << s;
            }
        }
    }
    // Every cell's two tables are CDFs from 0 to 1; the guided share is a candidate of
    // guided_shares x n / (n + n0) where light came back, 0 elsewhere.
    for (int s = 0; s < o.slots; ++s) {
        const float* cell = ta.data() + static_cast<size_t>(s) * ETK_GUIDE_CELL_FLOATS;
        // Read through the kernel's own accessors, so the layout is the one the kernels read.
        etk::EtkScene S{};
        S.guide_cells = ta.data();
        etk::EtkParams p{};
        p.guide_slots = o.slots;
        p.guide_continuation = 1;
        etk::EtkMaterial diffuse{};
        diffuse.type = ETK_MAT_DIFFUSE;
        const float* dir = etk::etk_cguide_cdf(S, p, s);
        for (const float* cdf : {cell, dir}) {
            EXPECT_EQ(cdf[0], 0.0f);
            EXPECT_EQ(cdf[K], 1.0f);
            for (int R = 0; R < K; ++R)
                EXPECT_LE(cdf[R], cdf[R + 1]);
        }
        const double n = 2.0 * dcount[s]; // every continuation record was added twice
        const double own = n / (n + o.prior);
        const float share = etk::etk_cguide_share(S, p, s, diffuse);
        const bool learned = s != dark && n > 0;
        bool candidate = false;
        for (int j = 0; j < ETK_GUIDED_CANDIDATES; ++j)
            candidate = candidate || std::fabs(share - etk::etk_guided_candidate(j) * own) < 1e-6;
        EXPECT_TRUE(candidate || (!learned && share == 0.0f)) << "slot " << s << ": " << share;
        if (!learned) { // nothing learned: uniform over the regions
            for (int R = 0; R <= K; ++R)
                EXPECT_NEAR(dir[R], float(R) / K, 1e-6);
        }
    }
}

// An update rewrites the tables of the slots with records since the last one, and names those
// floats (changed()): a device that copies only them (the native one) holds every update's
// tables, and a slot whose records stopped keeps its tables and is not copied again.
TEST(VisibilityGuideTables, UpdatesNameWhatTheyRewrite) {
    Fixture f;
    const auto cache = slab_cache(f);
    const et::VisibilityOptions o = sixty_four_slots();
    std::vector<float> device = et::guide_prior_cells(f.regions, o.slots, true, slab_box());
    std::mt19937 rng(21u);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    // n records of each kind in slots [first, end), light and continuation.
    auto record = [&](int first, int end, int n) {
        std::vector<int> keys(n), exits(n);
        std::vector<float> values(n), parts(2 * n), rays(8 * n, 0.0f);
        for (int i = 0; i < n; ++i) {
            keys[i] = (first + int(rng() % uint32_t(end - first))) * K + int(rng() % K);
            values[i] =
                rng() % 3 == 0 ? 0.0f : std::ldexp(float(rng() % 1000 + 1), -int(rng() % 12));
            exits[i] = values[i] > 0.0f ? int(rng() % ETK_PORTAL_CELLS) : -1;
            parts[2 * i] = std::ldexp(float(rng() % 1000 + 1), -int(rng() % 12));
            parts[2 * i + 1] = std::ldexp(float(rng() % 1000 + 1), -int(rng() % 12));
            float* r = &rays[8 * i];
            for (int k = 0; k < 3; ++k)
                r[k] = kSlabLo[k] + (kSlabHi[k] - kSlabLo[k]) * U(rng);
            const etk::float3 d =
                etk::normalize(etk::make_float3(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f));
            r[4] = d.x;
            r[5] = d.y;
            r[6] = d.z;
            r[7] = std::ldexp(float(rng() % 1000 + 1), -int(rng() % 12));
        }
        cache->add(keys.data(), values.data(), exits.data(), parts.data(), n);
        cache->add_continuations(keys.data(), values.data(), rays.data(), n);
    };
    // Whether any float of slot s's light table is in the spans.
    auto named = [&](int s) {
        const size_t a = size_t(s) * ETK_GUIDE_CELL_FLOATS, b = a + ETK_GUIDE_CELL_FLOATS;
        for (const auto& [first, end] : cache->changed())
            if (first < b && a < end)
                return true;
        return false;
    };
    auto update = [&]() {
        const std::vector<float>& t = cache->tables();
        for (const auto& [first, end] : cache->changed()) {
            if (first > end || end > t.size()) {
                ADD_FAILURE() << "span " << first << " .. " << end << " of " << t.size();
                return t;
            }
            std::copy(t.begin() + first, t.begin() + end, device.begin() + first);
        }
        EXPECT_TRUE(device == t) << "a float the update rewrote is not in its spans";
        return t;
    };
    record(0, 40, 6000);
    const std::vector<float> first = update();
    EXPECT_TRUE(named(10) && named(35));
    EXPECT_FALSE(named(50)); // no records: the prior, as the device holds it
    record(0, 20, 4000);     // slots 20 .. 39 learn nothing more
    const std::vector<float> second = update();
    EXPECT_TRUE(named(10));
    EXPECT_FALSE(named(35));
    for (int s : {25, 35}) { // the light table and the continuation guide's, as they were
        const size_t a = size_t(s) * ETK_GUIDE_CELL_FLOATS;
        EXPECT_TRUE(std::equal(first.begin() + a, first.begin() + a + ETK_GUIDE_CELL_FLOATS,
                               second.begin() + a));
        const size_t d = static_cast<size_t>(etk::etk_guide_dir_offset(o.slots, s));
        EXPECT_TRUE(std::equal(first.begin() + d, first.begin() + d + ETK_GUIDE_DIR_FLOATS,
                               second.begin() + d));
    }
    const size_t a = size_t(10) * ETK_GUIDE_CELL_FLOATS; // a slot with more records: new tables
    EXPECT_FALSE(std::equal(first.begin() + a, first.begin() + a + K, second.begin() + a));
}

// The share choice of both tables: the least second moment, a share > 0 charged `cost` of it;
// ties keep the smaller share.
TEST(VisibilityGuideTables, LeastMomentShareChargesTheCost) {
    const uint64_t m[4] = {100, 90, 80, 95};
    EXPECT_EQ(et::least_moment_share(m, 4, 0.0), 2u);
    EXPECT_EQ(et::least_moment_share(m, 4, 0.15), 2u); // 80 / 0.85 = 94 < 100
    EXPECT_EQ(et::least_moment_share(m, 4, 0.25), 0u); // 80 / 0.75 = 107 > 100
    const uint64_t tie[3] = {50, 50, 60};
    EXPECT_EQ(et::least_moment_share(tie, 3, 0.0), 0u);
    const uint64_t later[3] = {50, 40, 40};
    EXPECT_EQ(et::least_moment_share(later, 3, 0.0), 1u);
}

// The kernels' view of a cache's tables (guide_cells), ready: read through the kernels' own
// accessors, so the layout is the one the kernels read.
struct KernelView {
    std::vector<float> tables;
    etk::EtkScene S{};
    etk::EtkParams p{};
    KernelView(std::vector<float> t, int slots, bool continuation) : tables(std::move(t)) {
        S.guide_cells = tables.data();
        p.guide_slots = slots;
        p.guide_continuation = continuation ? 1 : 0;
        p.guide_ready = 1;
    }
    KernelView(const KernelView&) = delete; // S points into tables
};

// The light-sample count: the candidate of least (m_cont + m_light / n) (1 + cost n).
TEST(VisibilityGuideTables, LightSampleCountFollowsTheModel) {
    const double n[4] = {1.0, 0.5, 0.25, 0.125};
    EXPECT_EQ(et::light_sample_count(0.0, 1.0, 0.25, n, 4), 0.125); // light never gets through
    EXPECT_EQ(et::light_sample_count(1.0, 0.0, 0.25, n, 4), 1.0);   // all light is direct
    // 1.1 x 1.25 = 1.375, 1.2 x 1.125 = 1.35, 1.4 x 1.0625 = 1.4875, 1.8 x 1.03 = 1.86.
    EXPECT_EQ(et::light_sample_count(0.1, 1.0, 0.25, n, 4), 0.5);
    EXPECT_EQ(et::light_sample_count(0.0, 1.0, 0.0, n, 4), 1.0);  // free light samples: a tie
    EXPECT_EQ(et::light_sample_count(0.0, 0.0, 0.25, n, 4), 1.0); // no light at all: a tie too
}

// Options of four slots, and a cache of them over a 64 x 32 map (f) in the unit cube's box.
et::VisibilityOptions four_slots(bool continuation = true) {
    et::VisibilityOptions o;
    o.slots = 4;
    o.continuation = continuation;
    return o;
}
std::unique_ptr<et::VisibilityCache> small_cache(Fixture& f, const et::VisibilityOptions& o) {
    make(f, 64, 32, 5u);
    const float lo[3] = {0.0f, 0.0f, 0.0f}, hi[3] = {1.0f, 1.0f, 1.0f};
    return std::make_unique<et::VisibilityCache>(o, f.regions, 1.0, et::guide_portal_box(lo, hi));
}

// Each cell's light-sample count in the tables the kernels read (etk_guide_light_count): the
// model's choice where both kinds of records are plentiful, 1 elsewhere.
TEST(VisibilityGuideTables, LightSampleCountPerCell) {
    Fixture f;
    const et::VisibilityOptions o = four_slots();
    const std::unique_ptr<et::VisibilityCache> owned = small_cache(f, o);
    et::VisibilityCache& cache = *owned;
    // Slot 0: every shadow ray blocked, light comes back along the continuations. Slot 1: bright
    // unblocked light samples, dim continuations. Slot 2: blocked, but too few light records.
    // Slot 3: no records.
    std::vector<int> keys, exits, dkeys;
    std::vector<float> values, parts, dvalues, drays;
    auto light = [&](int slot, float v, int n) {
        for (int i = 0; i < n; ++i) {
            keys.push_back(slot * K + i % K);
            values.push_back(v);
            exits.push_back(v > 0.0f ? i % ETK_PORTAL_CELLS : -1);
            parts.push_back(0.5f);
            parts.push_back(0.5f);
        }
    };
    auto cont = [&](int slot, float v, int n) {
        for (int i = 0; i < n; ++i) {
            dkeys.push_back(slot * K + i % K);
            dvalues.push_back(v);
            const float r[8] = {0.5f, 0.5f, 0.5f, 0.0f, 0.0f, 1.0f, 0.0f, 0.3f};
            drays.insert(drays.end(), r, r + 8);
        }
    };
    const int n = 2 * o.min_records;
    light(0, 0.0f, n);
    cont(0, 1.0f, n);
    light(1, 10.0f, n);
    cont(1, 0.01f, n);
    light(2, 0.0f, o.min_records - 1);
    cont(2, 1.0f, n);
    cache.add(keys.data(), values.data(), exits.data(), parts.data(),
              static_cast<int>(keys.size()));
    cache.add_continuations(dkeys.data(), dvalues.data(), drays.data(),
                            static_cast<int>(dkeys.size()));
    KernelView v(cache.tables(), o.slots, true);
    EXPECT_EQ(etk::etk_guide_light_count(v.S, v.p, 0), 0.125f);
    EXPECT_EQ(etk::etk_guide_light_count(v.S, v.p, 1), 1.0f);
    EXPECT_EQ(etk::etk_guide_light_count(v.S, v.p, 2), 1.0f);
    EXPECT_EQ(etk::etk_guide_light_count(v.S, v.p, 3), 1.0f);
    // What the render summary reports: the cells below one light sample, per count.
    EXPECT_EQ(cache.fewer_light_samples(), (std::map<float, uint64_t>{{0.125f, 1u}}));
    v.p.guide_ready = 0; // before the first tables: every vertex takes its light sample
    EXPECT_EQ(etk::etk_guide_light_count(v.S, v.p, 0), 1.0f);
}

// Two directions in different regions of the continuation guide.
struct TwoDirections {
    etk::float3 d1 = etk::normalize(etk::make_float3(0.2f, 0.9f, 0.1f));
    etk::float3 d2 = etk::normalize(etk::make_float3(-0.6f, 0.3f, -0.5f));
    int R1 = etk::etk_cguide_region(d1), R2 = etk::etk_cguide_region(d2);
};

// The continuation guide learns the diffuse integrand, incident radiance x cosine: two regions
// whose records bring back the same luminance(L_in) / p, drawn at BSDF densities cos / pi of 0.9
// and 0.3 (the cell's share is still 0, so a record's density is its BSDF's), take learned
// probabilities 3 : 1 -- radiance alone would make them equal.
TEST(VisibilityGuideTables, ContinuationGuideFollowsRadianceTimesCosine) {
    Fixture f;
    et::VisibilityOptions o = four_slots();
    o.min_records = 1000; // the share before the cell chooses its own
    const std::unique_ptr<et::VisibilityCache> owned = small_cache(f, o);
    et::VisibilityCache& cache = *owned;
    const TwoDirections t;
    ASSERT_NE(t.R1, t.R2);
    const int slot = 1, n = 100;
    std::vector<int> keys;
    std::vector<float> values, rays;
    for (int i = 0; i < 2 * n; ++i) {
        const bool first = i < n;
        const etk::float3 d = first ? t.d1 : t.d2;
        keys.push_back(slot * K + (first ? t.R1 : t.R2));
        values.push_back(2.0f);
        const float r[8] = {0.5f, 0.5f, 0.5f, 0.0f,
                            d.x,  d.y,  d.z,  static_cast<float>((first ? 0.9 : 0.3) / M_PI)};
        rays.insert(rays.end(), r, r + 8);
    }
    cache.add_continuations(keys.data(), values.data(), rays.data(), static_cast<int>(keys.size()));
    KernelView v(cache.tables(), o.slots, true);
    const float* cdf = etk::etk_cguide_cdf(v.S, v.p, slot);
    // P(R) = own S(R) / sum S + (1 - own) / K, own = 2n / (2n + n0).
    const double own = 2.0 * n / (2.0 * n + o.prior), prior = (1.0 - own) / K;
    EXPECT_NEAR(cdf[t.R1 + 1] - cdf[t.R1] - prior, own * 0.75, 1e-5);
    EXPECT_NEAR(cdf[t.R2 + 1] - cdf[t.R2] - prior, own * 0.25, 1e-5);
    EXPECT_NEAR(cdf[ETK_GUIDE_DIR_SHARE], o.continuation_share * own, 1e-6);
}

// Each cell's guided share is the candidate whose continuation has the least second moment on
// all its records: after a first update has learned region R1 in two cells, a cell whose light
// keeps coming from R1 (where the guide is dense) takes the largest share, and a cell whose light
// comes from R2 (where the guide holds only its prior) takes none. Records drawn before the first
// update (the prior guide, uniform) do not count: the first update leaves continuation_share.
TEST(VisibilityGuideTables, GuidedShareHasTheLeastSecondMoment) {
    Fixture f;
    const et::VisibilityOptions o = four_slots();
    const std::unique_ptr<et::VisibilityCache> owned = small_cache(f, o);
    et::VisibilityCache& cache = *owned;
    const TwoDirections t;
    ASSERT_NE(t.R1, t.R2);
    const int n = 2 * o.min_records;
    // n records of `slot` along d, drawn at density cos / pi (every share is 0 when they are).
    auto records = [&](int slot, etk::float3 d, int R, float cos) {
        std::vector<int> keys(n, slot * K + R);
        std::vector<float> values(n, 2.0f), rays;
        for (int i = 0; i < n; ++i) {
            const float r[8] = {0.5f, 0.5f, 0.5f, 0.0f, d.x, d.y, d.z, cos * float(M_1_PI)};
            rays.insert(rays.end(), r, r + 8);
        }
        cache.add_continuations(keys.data(), values.data(), rays.data(), n);
    };
    auto share = [&](int slot) {
        KernelView v(cache.tables(), o.slots, true);
        return etk::etk_cguide_cdf(v.S, v.p, slot)[ETK_GUIDE_DIR_SHARE];
    };
    records(1, t.d1, t.R1, 0.9f);
    records(2, t.d1, t.R1, 0.9f);
    EXPECT_NEAR(share(1), o.continuation_share * n / (n + o.prior), 1e-6);
    records(1, t.d1, t.R1, 0.9f);
    records(2, t.d2, t.R2, 0.3f);
    const double own = 2.0 * n / (2.0 * n + o.prior);
    KernelView v(cache.tables(), o.slots, true);
    EXPECT_NEAR(etk::etk_cguide_cdf(v.S, v.p, 1)[ETK_GUIDE_DIR_SHARE],
                etk::etk_guided_candidate(ETK_GUIDED_CANDIDATES - 1) * own, 1e-6);
    EXPECT_EQ(etk::etk_cguide_cdf(v.S, v.p, 2)[ETK_GUIDE_DIR_SHARE], 0.0f);
}

// A cell chooses its portal share from the records since the last update: min_records - 1 before
// it and one after are too few (the share stays 0), min_records after the next are enough.
TEST(VisibilityGuideTables, SharesCountTheRecordsSinceTheLastUpdate) {
    Fixture f;
    const et::VisibilityOptions o = four_slots(false);
    const std::unique_ptr<et::VisibilityCache> owned = small_cache(f, o);
    et::VisibilityCache& cache = *owned;
    // Unblocked records of slot 0 whose direction the portal table draws 100 times more often
    // than the cell's mixture: the largest portal share has the least second moment.
    auto records = [&](int n) {
        std::vector<int> keys(n, 3), exits(n, 7);
        std::vector<float> values(n, 1.0f), parts;
        for (int i = 0; i < n; ++i) {
            parts.push_back(0.01f);
            parts.push_back(1.0f);
        }
        cache.add(keys.data(), values.data(), exits.data(), parts.data(), n);
    };
    auto share = [&] {
        KernelView v(cache.tables(), o.slots, false);
        return etk::etk_portal_share(v.S, v.p, 0);
    };
    records(o.min_records - 1);
    EXPECT_EQ(share(), 0.0f);
    records(1);
    EXPECT_EQ(share(), 0.0f) << "one record since the last update chose a share";
    records(o.min_records);
    EXPECT_EQ(share(), etk::etk_portal_candidate(ETK_PORTAL_CANDIDATES - 1));
}

} // namespace
