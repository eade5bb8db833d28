// The film (host/lib/render/film.h, kernels/film_accumulate.h): the mean, the per-pixel variance
// from the sums of squares, adding films, and resuming a render from its film: a render split into
// two runs, the second resuming from the first's film, equals the uninterrupted one bit for bit on
// both back ends. The exact sums (host/lib/render/film_sums.h): sample sets add in any order
// and partition to the same bits, so a render split by sample index (MPI ranks, farm tasks)
// equals the render in one process.
#include "render/film.h"
#include "render/film_sums.h"
#include "render_util.h"
#include "util/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

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
        means.push_back(r->sums().mean());
        if (k == 0)
            var_est = r->sums().variance_of_mean();
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
        const et::FilmSums saved = first->sums();
        auto second = et::make_renderer(ds);
        second->resume(saved);
        for (uint32_t k = 3; k < 6; ++k)
            second->render_sample(k);
        const et::FilmSums& a = whole->sums();
        const et::FilmSums& c = second->sums();
        EXPECT_TRUE(a == c);
        EXPECT_EQ(a.data()[a.pixels() / 2].count, 6u);
        EXPECT_THROW(second->resume(et::FilmSums(3, 3)), et::Error);
    }
}

// One pixel's pass film holding sample `v` (w = 1).
et::Film one_sample(float v) {
    et::Film f(1, 1);
    f.film_sum[0] = etk::make_float4(v, -v, 0.5f * v, 1.0f);
    f.film_sq[0] = etk::make_float4(v * v, v * v, 0.25f * v * v, 0.0f);
    return f;
}

TEST(FilmSums, FixedPointIsExactOnTheGrid) {
    EXPECT_TRUE(et::film_fixed_point(1.0f) == (et::int128(1) << 70));
    EXPECT_TRUE(et::film_fixed_point(-3.5f) == -(et::int128(7) << 69));
    EXPECT_TRUE(et::film_fixed_point(0.0f) == 0);
    EXPECT_TRUE(et::film_fixed_point(1e-30f) == 0); // below half a unit of 2^-70
    const float big = 1.5e16f;
    EXPECT_EQ(et::film_fixed_to_double(et::film_fixed_point(big)), double(big));
    // Every float above 2^-46 is held exactly: back to the same float.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> exponent(-45.0f, 50.0f);
    for (int i = 0; i < 10000; ++i) {
        const float v = std::ldexp(1.0f + float(rng() % 1000) / 1000.0f, int(exponent(rng)));
        ASSERT_EQ(float(et::film_fixed_to_double(et::film_fixed_point(v))), v) << v;
    }
}

// Samples of a wide dynamic range (fireflies next to faint paths): a float sum depends on the
// order, the exact sums on nothing: any order, any split into parts added in any order.
TEST(FilmSums, AnyOrderAndPartitionGiveTheSameBits) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> exponent(-30.0f, 27.0f); // squares below 2^56
    std::vector<float> samples(257);
    for (float& v : samples)
        v = std::exp2(exponent(rng)) * (rng() % 7 == 0 ? -1.0f : 1.0f);
    et::FilmSums whole(1, 1);
    float naive = 0.0f;
    for (float v : samples) {
        whole.add_pass(one_sample(v));
        naive += v;
    }
    std::vector<float> shuffled = samples;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    float naive_shuffled = 0.0f;
    for (float v : shuffled)
        naive_shuffled += v;
    EXPECT_NE(naive, naive_shuffled) << "float sums of this set should depend on the order";
    for (int parts : {2, 3, 4, 16}) {
        std::vector<et::FilmSums> p(parts, et::FilmSums(1, 1));
        for (size_t i = 0; i < shuffled.size(); ++i)
            p[i % parts].add_pass(one_sample(shuffled[i]));
        et::FilmSums total(1, 1);
        for (int k = parts - 1; k >= 0; --k) // reverse rank order, on purpose
            total.add(p[k]);
        EXPECT_TRUE(total == whole) << parts << " parts";
        EXPECT_EQ(total.mean(), whole.mean());
    }
    EXPECT_EQ(whole.data()[0].count, samples.size());
    EXPECT_THROW(whole.add(et::FilmSums(2, 1)), et::Error);
}

// Large films are folded on several threads (add_pass splits the pixels): the same bits as one
// thread, AOVs and special values included.
TEST(FilmSums, FoldOnThreadsEqualsOneThread) {
    const int w = 300, h = 250; // past kParallelFoldPixels
    ASSERT_GE(size_t(w) * h, et::FilmSums::kParallelFoldPixels);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> exponent(-30.0f, 27.0f);
    auto value = [&] {
        const uint32_t k = rng() % 101;
        if (k == 0)
            return std::numeric_limits<float>::infinity();
        if (k == 1)
            return std::nanf("");
        return std::exp2(exponent(rng)) * (k % 7 == 0 ? -1.0f : 1.0f);
    };
    et::FilmSums one(w, h, true), three(w, h, true);
    for (int pass = 0; pass < 3; ++pass) {
        et::Film f(w, h);
        for (size_t i = 0; i < f.pixels(); ++i) {
            const float r = value(), g = value(), b = value();
            f.film_sum[i] = {r, g, b, 1.0f};
            f.film_sq[i] = {r * r, g * g, b * b, 0.0f};
            f.film_albedo[i] = {value(), value(), value(), float(rng() % 2)};
            f.film_normal[i] = {value(), value(), value(), value()};
        }
        one.add_pass(f, 1);
        three.add_pass(f, 3);
    }
    EXPECT_TRUE(one == three); // sums, counts, flags and AOVs, bytewise
}

TEST(FilmSums, MeanVarianceAndSpecialValues) {
    et::FilmSums f(1, 1);
    for (float v : {1.0f, 2.0f, 6.0f})
        f.add_pass(one_sample(v));
    const std::vector<float> m = f.mean(), var = f.variance_of_mean();
    EXPECT_EQ(m[0], 3.0f);
    EXPECT_EQ(m[1], -3.0f);
    EXPECT_EQ(m[2], 1.5f);
    EXPECT_NEAR(var[0], 7.0 / 3.0, 1e-6); // s^2 = 7, over n = 3
    // A pass without a sample (w = 0) changes nothing.
    et::FilmSums g = f;
    g.add_pass(et::Film(1, 1));
    EXPECT_TRUE(g == f);
    // Not finite, or beyond 2^56: the channel becomes what a float sum would be.
    et::FilmSums h = f;
    h.add_pass(one_sample(std::numeric_limits<float>::infinity()));
    EXPECT_EQ(h.mean()[0], std::numeric_limits<float>::infinity());
    EXPECT_EQ(h.mean()[1], -std::numeric_limits<float>::infinity());
    h.add_pass(one_sample(std::nanf("")));
    EXPECT_TRUE(std::isnan(h.mean()[0]));
    et::FilmSums k = f;
    k.add_pass(one_sample(1e20f));
    EXPECT_EQ(k.mean()[0], std::numeric_limits<float>::infinity());
    // Flags travel through add like the sums.
    et::FilmSums sum = f;
    sum.add(k);
    EXPECT_EQ(sum.mean()[0], std::numeric_limits<float>::infinity());
    EXPECT_EQ(et::FilmSums(1, 1).mean()[0], 0.0f); // no sample: 0
}

// Renderers given disjoint sample indices (interleaved, as MPI ranks take them, and ranges, as
// farm tasks do) add up to the film of one renderer, bit for bit, on both back ends.
TEST(FilmSums, SplitRenderEqualsOneRenderer) {
    const et::Scene s = small_scene();
    for (et::Backend b : {et::Backend::cpu, et::Backend::opencl}) {
        SCOPED_TRACE(et::name_of(b));
        et::RenderSettings st = s.settings;
        st.backend = b;
        st.threads = 2;
        const et::DeviceScene ds = et::prepare_device_scene(s, st);
        auto whole = et::make_renderer(ds);
        for (uint32_t k = 0; k < 7; ++k)
            whole->render_sample(k);
        auto even = et::make_renderer(ds), odd = et::make_renderer(ds);
        for (uint32_t k = 0; k < 7; ++k)
            (k % 2 ? odd : even)->render_sample(k);
        et::FilmSums split = odd->sums();
        split.add(even->sums());
        EXPECT_TRUE(split == whole->sums());
        auto head = et::make_renderer(ds), tail = et::make_renderer(ds);
        for (uint32_t k = 0; k < 7; ++k)
            (k < 3 ? head : tail)->render_sample(k);
        et::FilmSums ranges = tail->sums();
        ranges.add(head->sums());
        EXPECT_TRUE(ranges == whole->sums());
        EXPECT_EQ(ranges.mean(), whole->image());
    }
}

} // namespace
