// The AOVs (kernels/aov.h, render/film_aovs.h) and the per-pixel variance estimate
// (FilmSums::variance_of_mean, the EXR's variance layer and --noise-target's error):
// - a diffuse quad facing the camera at a known distance: its albedo, normal and depth, on both
//   back ends, everywhere in the image; a pixel that no sample hits reads depth kNoHitDepth;
// - the AOV sums, like the radiance's, are exact: a render split into sample ranges and added
//   in any order, and its state written and read back, are the single render bit for bit;
// - the variance estimate against the empirical variance of the means of independent renders
//   (32 seeds), within a bound derived from the variance of both (5 sigma): equal in
//   expectation for the random sampler, an upper bound in practice for Sobol';
// - relative_error falls as 1/sqrt(n) (random sampler): 4x the samples, half the error.
#include "render/film_layers.h"
#include "render/noise_estimate.h"
#include "render/render_state.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

// A diffuse quad (albedo 0.6, 0.3, 0.2) in the plane z = 0 facing the camera at (0, 0, 5),
// filling the view; a bright spot in the map so that the pixels have variance.
et::Scene quad_scene(bool fill = true) {
    et::RgbImage map = ett::constant_image(32, 16, 1.0f);
    for (int c = 0; c < 3; ++c)
        map.at(20, 4)[c] = 200.0f;
    et::Scene s = ett::base_scene(12, 8, et::make_envmap("spot", std::move(map), {}));
    s.camera.eye = {0, 0, 5};
    s.camera.target = {0, 0, 0};
    s.camera.fov_deg = 40.0f;
    et::Material m = ett::diffuse(0.5f);
    m.albedo = glm::vec3(0.6f, 0.3f, 0.2f);
    s.materials.push_back(m);
    ett::add_square(s.triangles, glm::vec3(fill ? 0.0f : 1.4f, 0, 0), glm::vec3(0, 0, 1),
                    fill ? 10.0f : 1.0f, 0);
    s.settings.max_depth = 2;
    s.settings.aovs = true;
    return s;
}

et::FilmSums render_sums(const et::Scene& scene, const std::string& backend, int first, int end,
                         uint32_t seed = 1, et::SamplerKind sampler = et::SamplerKind::random) {
    et::RenderSettings st = scene.settings;
    st.backend = et::parse_backend(backend, "test");
    st.threads = 2;
    st.seed = seed;
    st.sampler = sampler;
    const et::DeviceScene ds = et::prepare_device_scene(scene, st);
    auto r = et::make_renderer(ds);
    for (int k = first; k < end; ++k)
        r->render_sample(static_cast<uint32_t>(k));
    return r->sums();
}

class AovBackends : public ::testing::TestWithParam<std::string> {};

TEST_P(AovBackends, QuadAlbedoNormalDepth) {
    const et::FilmSums sums = render_sums(quad_scene(), GetParam(), 0, 4);
    ASSERT_TRUE(sums.has_aovs());
    const et::AovImages aov = sums.aov_images();
    for (size_t i = 0; i < sums.pixels(); ++i) {
        SCOPED_TRACE("pixel " + std::to_string(i));
        EXPECT_EQ(sums.data()[i].count, 4u);
        EXPECT_EQ(sums.aov_data()[i].hits, 4u);
        EXPECT_NEAR(aov.albedo[3 * i + 0], 0.6f, 1e-6);
        EXPECT_NEAR(aov.albedo[3 * i + 1], 0.3f, 1e-6);
        EXPECT_NEAR(aov.albedo[3 * i + 2], 0.2f, 1e-6);
        EXPECT_NEAR(aov.normal[3 * i + 0], 0.0f, 1e-6);
        EXPECT_NEAR(aov.normal[3 * i + 1], 0.0f, 1e-6);
        EXPECT_NEAR(aov.normal[3 * i + 2], 1.0f, 1e-6);
        EXPECT_NEAR(aov.depth[i], 5.0f, 5e-5); // camera-axis depth: the plane's distance
    }
}

// A small quad right of the centre: pixels it covers hold its AOVs, pixels no sample of which
// hits it hold zeros and depth kNoHitDepth, and a pixel its edge crosses averages albedo over
// all samples but depth over the hits only.
TEST_P(AovBackends, MissesAndPartialCoverage) {
    const et::FilmSums sums = render_sums(quad_scene(false), GetParam(), 0, 16);
    const et::AovImages aov = sums.aov_images();
    int inside = 0, outside = 0, partial = 0;
    for (size_t i = 0; i < sums.pixels(); ++i) {
        const uint32_t hits = sums.aov_data()[i].hits;
        if (hits == 0) {
            ++outside;
            EXPECT_EQ(aov.depth[i], et::kNoHitDepth);
            EXPECT_EQ(aov.albedo[3 * i], 0.0f);
            EXPECT_EQ(aov.normal[3 * i + 2], 0.0f);
            continue;
        }
        inside += hits == 16u;
        partial += hits < 16u;
        EXPECT_NEAR(aov.depth[i], 5.0f, 5e-5) << i;
        EXPECT_NEAR(aov.albedo[3 * i], 0.6f * float(hits) / 16.0f, 1e-6) << i;
        EXPECT_NEAR(aov.normal[3 * i + 2], float(hits) / 16.0f, 1e-6) << i;
    }
    EXPECT_GT(inside, 0);
    EXPECT_GT(outside, 0);
    EXPECT_GT(partial, 0);
}

INSTANTIATE_TEST_SUITE_P(Both, AovBackends, ::testing::Values("opencl", "cpu"));

TEST(AovSums, SplitsAndStatesGiveTheSameBits) {
    const et::Scene scene = quad_scene(false);
    const et::FilmSums one = render_sums(scene, "cpu", 0, 9);
    et::FilmSums parts = render_sums(scene, "cpu", 5, 9);
    parts.add(render_sums(scene, "cpu", 0, 2));
    parts.add(render_sums(scene, "cpu", 2, 5));
    EXPECT_TRUE(parts == one);
    // Perturb one AOV sum: == sees it.
    et::FilmSums other = one;
    other.aov_data()[3].sum[et::AovPixel::kDepth] += 1;
    EXPECT_FALSE(other == one);
    // A film without AOVs does not add to one with them.
    EXPECT_THROW(parts.add(et::FilmSums(one.width(), one.height())), et::Error);

    // The state holds the AOV sums; a render without --aovs refuses it by name.
    const std::string dir = ett::scratch_dir("aov_state");
    et::RenderSettings st = scene.settings;
    st.backend = et::Backend::cpu;
    const et::DeviceScene ds = et::prepare_device_scene(scene, st);
    const et::RenderState state{et::render_key(ds), 9, 0, one};
    et::write_render_state(dir + "/a.state", state);
    const et::RenderState back = et::read_render_state(dir + "/a.state");
    EXPECT_TRUE(back.sums == one);
    EXPECT_NO_THROW(et::check_render_state(back, ds, "a.state"));
    st.aovs = false;
    const et::DeviceScene plain = et::prepare_device_scene(scene, st);
    EXPECT_NE(et::render_key(plain), et::render_key(ds));
    try {
        et::check_render_state(back, plain, "a.state");
        ADD_FAILURE() << "a state with AOVs continued a render without";
    } catch (const et::Error& e) {
        EXPECT_NE(std::string(e.what()).find("AOVs"), std::string::npos) << e.what();
    }

    // The EXR layers: names, and the values at a covered pixel.
    const et::FilmLayers layers = et::film_layers(one);
    ASSERT_EQ(layers.names.size(), 13u);
    EXPECT_EQ(layers.names[3], "albedo.R");
    EXPECT_EQ(layers.names[6], "N.X");
    EXPECT_EQ(layers.names[9], "Z");
    EXPECT_EQ(layers.names[12], "variance.B");
    ASSERT_EQ(layers.pixels.size(), 13u * one.pixels());
    const std::vector<float> var = one.variance_of_mean();
    for (size_t i = 0; i < one.pixels(); ++i)
        EXPECT_EQ(layers.pixels[13 * i + 10], var[3 * i]);
}

// The estimate of the variance of a pixel's mean, against the variance of the means of K
// renders with independent seeds, summed over the pixels (channel G; pixels are independent,
// channels are not). The bound is 5 sigma of the difference, sigma from the spread of both
// sides: the sample variance of K values has variance (m4 - s^4 (K - 3) / (K - 1)) / K, the
// estimate averaged over K renders s_est^2 / K.
struct VarianceCheck {
    double empirical = 0, estimated = 0, sigma = 0;
};
VarianceCheck check_variance(et::SamplerKind sampler) {
    const et::Scene scene = quad_scene(false);
    constexpr int K = 32, n = 8;
    std::vector<std::vector<float>> means, vars;
    for (int k = 0; k < K; ++k) {
        const et::FilmSums s = render_sums(scene, "cpu", 0, n, 1000u + uint32_t(k), sampler);
        means.push_back(s.mean());
        vars.push_back(s.variance_of_mean());
    }
    VarianceCheck c;
    double var_emp = 0, var_est = 0;
    for (size_t i = 1; i < means[0].size(); i += 3) {
        double m = 0, e = 0;
        for (int k = 0; k < K; ++k) {
            m += means[k][i] / K;
            e += vars[k][i] / K;
        }
        double s2 = 0, m4 = 0, se2 = 0;
        for (int k = 0; k < K; ++k) {
            const double d = means[k][i] - m, de = vars[k][i] - e;
            s2 += d * d / (K - 1);
            m4 += d * d * d * d / K;
            se2 += de * de / (K - 1);
        }
        c.empirical += s2;
        c.estimated += e;
        var_emp += std::max(0.0, (m4 - s2 * s2 * (K - 3.0) / (K - 1.0)) / K);
        var_est += se2 / K;
    }
    c.sigma = std::sqrt(var_emp + var_est);
    return c;
}

TEST(VarianceEstimate, MatchesIndependentRendersWithTheRandomSampler) {
    const VarianceCheck c = check_variance(et::SamplerKind::random);
    ASSERT_GT(c.estimated, 0.0);
    EXPECT_LT(std::fabs(c.empirical - c.estimated), 5.0 * c.sigma)
        << "empirical " << c.empirical << ", estimated " << c.estimated << ", sigma " << c.sigma;
    EXPECT_LT(c.sigma, 0.2 * c.estimated) << "the test must be able to tell a factor 2";
}

TEST(VarianceEstimate, BoundsIndependentRendersWithSobol) {
    const VarianceCheck c = check_variance(et::SamplerKind::sobol);
    ASSERT_GT(c.estimated, 0.0);
    EXPECT_LT(c.empirical, c.estimated + 5.0 * c.sigma)
        << "empirical " << c.empirical << ", estimated " << c.estimated << ", sigma " << c.sigma;
    std::printf("Sobol', %s: empirical variance of the mean %.4g, estimated %.4g (ratio %.3f), "
                "sigma %.2g\n",
                "32 seeds x 8 spp", c.empirical, c.estimated, c.empirical / c.estimated, c.sigma);
}

TEST(NoiseEstimate, RelativeErrorHalvesWithFourTimesTheSamples) {
    const et::Scene scene = quad_scene();
    const double e8 = et::relative_error(render_sums(scene, "cpu", 0, 16));
    const double e32 = et::relative_error(render_sums(scene, "cpu", 0, 64));
    ASSERT_GT(e8, 0.0);
    EXPECT_NEAR(e32 / e8, 0.5, 0.15) << e8 << " " << e32;
    EXPECT_EQ(et::relative_error(render_sums(scene, "cpu", 0, 1)),
              std::numeric_limits<double>::infinity());
    EXPECT_EQ(et::next_noise_check(16, 0.2, 0.1), 32);  // at most doubling
    EXPECT_EQ(et::next_noise_check(16, 0.11, 0.1), 20); // where 1/sqrt(n) meets the target
    EXPECT_EQ(et::next_noise_check(16, 0.05, 0.1), 17);
}

} // namespace
