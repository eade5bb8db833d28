// The film (host/lib/render/film.h, kernels/film.h): the mean, the per-pixel variance from the
// sums of squares, adding films, and resuming a render from its film: a render split into two
// runs, the second resuming from the first's film, equals the uninterrupted one bit for bit on
// both back ends.
#include "render/film.h"
#include "render_util.h"
#include "util/error.h"

#include <gtest/gtest.h>

#include <cstring>

namespace {

et::Scene small_scene() {
    et::Scene s =
        ett::base_scene(24, 16, et::make_envmap("sky", ett::constant_image(32, 16, 1.0f), {}));
    s.camera.eye = {0, 1, 3};
    s.materials.push_back(ett::diffuse(0.5f));
    const glm::vec3 p[3] = {{-2, 0, -2}, {2, 0, -2}, {0, 0, 2}};
    const glm::vec3 n[3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    et::add_triangle(s.triangles, p, n, 0);
    s.settings.max_depth = 3;
    return s;
}

TEST(Film, MeanAndVarianceFromSums) {
    et::Film f(2, 1);
    const float xs[] = {1.0f, 2.0f, 4.0f, 5.0f};
    for (float x : xs) {
        f.film_sum[0] = etk::make_float4(f.film_sum[0].x + x, f.film_sum[0].y + 2 * x,
                                         f.film_sum[0].z, f.film_sum[0].w + 1);
        f.film_sq[0] = etk::make_float4(f.film_sq[0].x + x * x, f.film_sq[0].y + 4 * x * x, 0, 0);
    }
    const std::vector<float> m = f.mean(), v = f.variance_of_mean();
    EXPECT_FLOAT_EQ(m[0], 3.0f);
    EXPECT_FLOAT_EQ(m[1], 6.0f);
    // sample variance of {1, 2, 4, 5} is 10/3; of the mean, 10/12
    EXPECT_NEAR(v[0], 10.0 / 12.0, 1e-6);
    EXPECT_NEAR(v[1], 4 * 10.0 / 12.0, 1e-5);
    EXPECT_EQ(v[2], 0.0f);
    EXPECT_EQ(m[3], 0.0f); // a pixel without samples
    EXPECT_EQ(v[3], 0.0f);
}

TEST(Film, AddSumsAndRefusesOtherSizes) {
    et::Film a(3, 2), b(3, 2), c(2, 3);
    a.film_sum[4] = etk::make_float4(1, 2, 3, 1);
    b.film_sum[4] = etk::make_float4(3, 2, 1, 1);
    b.film_sq[4] = etk::make_float4(9, 4, 1, 0);
    a.add(b);
    EXPECT_EQ(a.film_sum[4].x, 4.0f);
    EXPECT_EQ(a.film_sum[4].w, 2.0f);
    EXPECT_EQ(a.film_sq[4].x, 9.0f);
    EXPECT_THROW(a.add(c), et::Error);
}

// The variance the film estimates matches the spread of independent renders' pixel means.
TEST(Film, VarianceEstimateMatchesSpreadAcrossSeeds) {
    et::Scene s = small_scene();
    s.settings.max_depth = 1;
    s.settings.strategy = et::Strategy::uniform; // noisy on purpose
    s.settings.backend = et::Backend::cpu;
    const int seeds = 24, spp = 16;
    std::vector<std::vector<float>> means;
    std::vector<float> var_est;
    for (int k = 0; k < seeds; ++k) {
        et::RenderSettings st = s.settings;
        st.seed = 100 + k;
        const et::DeviceScene ds = et::prepare_device_scene(s, st);
        auto r = et::make_renderer(ds);
        for (int i = 0; i < spp; ++i)
            r->render_sample(i);
        means.push_back(r->film().mean());
        if (k == 0)
            var_est = r->film().variance_of_mean();
    }
    // Average over the pixels of (spread across seeds) / (film estimate).
    double ratio = 0.0;
    int used = 0;
    for (size_t i = 0; i < var_est.size(); i += 3) {
        double m = 0.0, m2 = 0.0;
        for (const auto& img : means) {
            m += img[i];
            m2 += double(img[i]) * img[i];
        }
        m /= seeds;
        const double spread = (m2 / seeds - m * m) * seeds / (seeds - 1);
        if (var_est[i] > 1e-8 && spread > 1e-8) {
            ratio += spread / var_est[i];
            ++used;
        }
    }
    ASSERT_GT(used, 100);
    ratio /= used;
    // Each estimate has ~2/15 relative variance; averaged over hundreds of pixels the ratio is 1
    // within a few percent (the per-pixel ratio's mean is biased up by ~1/(n-3) ~ 8%).
    EXPECT_GT(ratio, 0.8);
    EXPECT_LT(ratio, 1.35);
}

TEST(Film, ResumedRenderEqualsUninterrupted) {
    const et::Scene s = small_scene();
    for (et::Backend b : {et::Backend::cpu, et::Backend::opencl}) {
        SCOPED_TRACE(et::name_of(b));
        et::RenderSettings st = s.settings;
        st.backend = b;
        st.threads = 2;
        const et::DeviceScene ds = et::prepare_device_scene(s, st);
        auto whole = et::make_renderer(ds);
        for (uint32_t k = 0; k < 6; ++k)
            whole->render_sample(k);
        auto first = et::make_renderer(ds);
        for (uint32_t k = 0; k < 3; ++k)
            first->render_sample(k);
        const et::Film saved = first->film();
        auto second = et::make_renderer(ds);
        second->resume(saved);
        for (uint32_t k = 3; k < 6; ++k)
            second->render_sample(k);
        const et::Film& a = whole->film();
        const et::Film& c = second->film();
        EXPECT_EQ(
            0, std::memcmp(a.film_sum.data(), c.film_sum.data(), a.pixels() * sizeof(etk::float4)));
        EXPECT_EQ(
            0, std::memcmp(a.film_sq.data(), c.film_sq.data(), a.pixels() * sizeof(etk::float4)));
        EXPECT_GT(a.film_sum[a.pixels() / 2].w, 5.0f);
        EXPECT_THROW(second->resume(et::Film(3, 3)), et::Error);
    }
}

} // namespace
