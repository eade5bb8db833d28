// Stage bookkeeping of the integrator (kernels/integrator.h, path_state.h): film accumulation
// drops and counts a non-finite path radiance (renders report it instead of writing NaN), a
// stage's queue pushes land where the next stage reads them, and intersect sends each ray its own
// way: a hit to the shade queue, an escaped ray to the environment's light, a hit past the last
// bounce nowhere.
#include "kernels/integrator.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

TEST(Integrator, AccumulateDropsAndCountsNonFiniteSamples) {
    using etk::float4;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float4> radiance = {
        {1, 2, 3, 0}, {nan, 0, 0, 0}, {0, inf, 0, 0}, {0.5f, 0.5f, 0.5f, 0}};
    std::vector<int> pixel = {0, 1, 2, 0};
    std::vector<float4> film(3, float4{0, 0, 0, 0}), film_sq(3, float4{0, 0, 0, 0});
    uint32_t counters[etk::ETK_Q_COUNT] = {};
    etk::EtkPaths P{};
    P.radiance = radiance.data();
    P.pixel = pixel.data();
    etk::EtkQueues Q{};
    Q.counters = counters;
    etk::EtkFilm F{}; // accumulate writes the radiance sums only
    F.film_sum = film.data();
    F.film_sq = film_sq.data();
    for (int i = 0; i < 4; ++i) {
        etk::EtkPushes out = etk::etk_no_pushes();
        etk::etk_accumulate(etk::EtkScene{}, P, Q, F, etk::EtkParams{}, i, &out);
        for (int q = 0; q < ETK_PUSH_QUEUES; ++q)
            EXPECT_EQ(out.slot[q], -1); // accumulating ends the path: nothing is queued
    }
    EXPECT_EQ(counters[etk::ETK_Q_NONFINITE], 2u);
    EXPECT_FLOAT_EQ(film_sq[0].x, 1.25f); // 1^2 + 0.5^2: the sums of squares
    EXPECT_FLOAT_EQ(film_sq[0].z, 9.25f);
    EXPECT_FLOAT_EQ(film[0].x, 1.5f);
    EXPECT_FLOAT_EQ(film[0].w, 2.0f); // both samples counted towards the pixel's mean
    for (int p = 1; p < 3; ++p) {
        EXPECT_TRUE(std::isfinite(film[p].x) && std::isfinite(film[p].y) &&
                    std::isfinite(film[p].z));
        EXPECT_EQ(film[p].w, 1.0f);
    }
}

// A stage's pushes land in the queue of their counter, each at the next free index, in counter
// order; slots of -1 push nothing.
TEST(Integrator, PushesLandInTheirCountersQueues) {
    std::vector<int> ray_out(4, -7), shade(4, -7), shadow(4, -7);
    uint32_t counters[etk::ETK_Q_COUNT] = {};
    etk::EtkQueues Q{};
    Q.ray_out = ray_out.data();
    Q.shade = shade.data();
    Q.shadow = shadow.data();
    Q.counters = counters;
    etk::EtkPushes a = etk::etk_no_pushes();
    a.slot[etk::ETK_Q_SHADE] = 5;
    a.slot[etk::ETK_Q_SHADOW] = 6;
    etk::etk_push_each(Q, &a);
    etk::EtkPushes b = etk::etk_no_pushes();
    b.slot[etk::ETK_Q_SHADE] = 9;
    b.slot[etk::ETK_Q_RAY_OUT] = 0;
    etk::etk_push_each(Q, &b);
    etk::EtkPushes none = etk::etk_no_pushes();
    etk::etk_push_each(Q, &none);
    EXPECT_EQ(counters[etk::ETK_Q_RAY_OUT], 1u);
    EXPECT_EQ(counters[etk::ETK_Q_SHADE], 2u);
    EXPECT_EQ(counters[etk::ETK_Q_SHADOW], 1u);
    EXPECT_EQ(ray_out[0], 0);
    EXPECT_EQ(ray_out[1], -7);
    EXPECT_EQ(shade[0], 5);
    EXPECT_EQ(shade[1], 9);
    EXPECT_EQ(shade[2], -7);
    EXPECT_EQ(shadow[0], 6);
    EXPECT_EQ(shadow[1], -7);
}

// One square facing +z at z = 0 under a constant map of radiance 2, three rays from z = 1:
// down onto the square (depth 0 of max 2: queued for shading, its hit written), up into the sky
// (it takes beta x 2 at once, with no queue), and down again at depth 2 (the path ends: nothing
// queued, nothing written, no light).
TEST(Integrator, IntersectQueuesHitsLightsEscapesAndEndsAtTheLastBounce) {
    using etk::float4;
    et::Scene sc =
        ett::base_scene(4, 4, et::make_envmap("sky", ett::constant_image(16, 8, 2.0f), {}));
    sc.materials.push_back(ett::diffuse(0.5f));
    ett::add_square(sc.triangles, glm::vec3(0.0f), glm::vec3(0, 0, 1), 1.0f, 0);
    sc.settings.max_depth = 2;
    const et::DeviceScene d = et::prepare_device_scene(sc, sc.settings);
    std::vector<float4> ray_o(3, float4{0, 0, 1, 0});
    std::vector<float4> ray_d = {{0, 0, -1, 0}, {0, 0, 1, 0}, {0, 0, -1, 0}};
    std::vector<int> depth = {0, 0, 2};
    std::vector<float> ray_pdf(3, -1.0f); // camera rays: no MIS weight at an escape
    std::vector<float4> beta(3, float4{0.5f, 0.25f, 1.0f, 0});
    std::vector<float4> radiance(3, float4{0, 0, 0, 0}), hit(3, float4{-9, -9, -9, -9});
    std::vector<int> ray_in = {0, 1, 2};
    uint32_t counters[etk::ETK_Q_COUNT] = {};
    etk::EtkPaths P{}; // what intersect and the escaped light read and write, nothing else
    P.ray_o = ray_o.data();
    P.ray_d = ray_d.data();
    P.depth = depth.data();
    P.ray_pdf = ray_pdf.data();
    P.beta = beta.data();
    P.radiance = radiance.data();
    P.hit = hit.data();
    etk::EtkQueues Q{};
    Q.ray_in = ray_in.data();
    Q.counters = counters;
    etk::EtkPushes out[3];
    for (int i = 0; i < 3; ++i) {
        out[i] = etk::etk_no_pushes();
        etk::etk_intersect(d.view(), P, Q, etk::EtkFilm{}, d.params, i, &out[i]);
    }
    EXPECT_EQ(out[0].slot[etk::ETK_Q_SHADE], 0);
    EXPECT_FLOAT_EQ(hit[0].x, 1.0f);
    EXPECT_EQ(radiance[0].x, 0.0f);
    EXPECT_EQ(out[1].slot[etk::ETK_Q_SHADE], -1);
    EXPECT_FLOAT_EQ(radiance[1].x, 1.0f); // beta x 2
    EXPECT_FLOAT_EQ(radiance[1].y, 0.5f);
    EXPECT_FLOAT_EQ(radiance[1].z, 2.0f);
    EXPECT_EQ(hit[1].x, -9.0f);
    EXPECT_EQ(out[2].slot[etk::ETK_Q_SHADE], -1);
    EXPECT_EQ(hit[2].x, -9.0f);
    EXPECT_EQ(radiance[2].x, 0.0f);
    for (const etk::EtkPushes& o : out) // intersect queues nothing else
        for (int q : {etk::ETK_Q_RAY_OUT, etk::ETK_Q_SHADOW})
            EXPECT_EQ(o.slot[q], -1);
}

// Russian roulette (etk_shade) ends paths only past their first rr_depth surfaces. In a closed
// diffuse room (albedo 0.7, lit through one open side) at depth 4: rr_depth 4 cuts no path, so
// its image is rr_depth 1000's bit for bit (an off-by-one that let the roulette cut the last
// continuation, which can only reach the map, would change it), while rr_depth 3 cuts the last
// continuation (an off-by-one the other way would leave it whole); rr_depth 0 cuts from the
// first surface on, converges to the same image (another seed: independent renders) and pays
// for the rays it saves in variance.
TEST(Roulette, CutsOnlyPastItsDepthAndKeepsTheImage) {
    et::Scene s = ett::side_lit_room(16, 12);
    s.settings.max_depth = 4;
    s.settings.strategy = et::Strategy::mis;
    auto with_depth = [&](int rr_depth, int spp, uint32_t seed) {
        et::Scene v = s;
        v.settings.rr_depth = rr_depth;
        v.settings.seed = seed;
        return ett::render(v, "cpu", spp);
    };
    const ett::RenderResult never = with_depth(1000, 256, 1), at_max = with_depth(4, 256, 1),
                            early = with_depth(0, 256, 2);
    EXPECT_EQ(never.mean, at_max.mean);
    EXPECT_NE(with_depth(3, 4, 1).mean, with_depth(1000, 4, 1).mean);
    const ett::Agreement g = ett::agreement(early, never);
    std::printf("agreement: mean z^2 %.3f, image means' z %.2f, |z| > 4: %.4f\n", g.mean_z2,
                g.mean_z, g.frac_over_4);
    EXPECT_LT(g.mean_z2, 1.3);
    EXPECT_GT(g.mean_z2, 0.7); // the variances are estimated well enough for the z test to bite
    EXPECT_LT(std::fabs(g.mean_z), 5.0);
    EXPECT_LE(g.frac_over_4, 0.005);
    double v_early = 0.0, v_never = 0.0;
    for (size_t i = 0; i < never.var.size(); ++i) {
        v_early += early.var[i];
        v_never += never.var[i];
    }
    std::printf("variance per pass, summed: roulette from surface 1 %.4g, none %.4g\n", v_early,
                v_never);
    EXPECT_GT(v_early, 1.2 * v_never);
}
