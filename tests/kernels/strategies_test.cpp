// The light, bsdf, mis, compensated, visibility and cosine strategies (and either GGX sampling
// and mis split into several light and BSDF samples per vertex) estimate the same integral, so
// they converge to the same image; and the error of an unbiased estimator with independent
// samples falls as 1/sqrt(spp).
//
// Noise: every render uses the random sampler (independent passes), and the per-pixel variance
// of the mean is measured from the passes (render_util.h). Two renders of the same image give
// z = (a - b) / sd per pixel channel: the test first checks that this noise estimate is
// calibrated on two seeds of the same strategy (mean z^2 ~ 1), then holds every pair of
// strategies to the same statistics. Bounds: mean z^2 <= 1.3 (its standard error over
// 32 x 32 x 3 values is ~0.03 for Gaussian z, a few times that with heavy tails); |z| > 4 in at
// most 0.5% of the values (6e-5 expected for a Gaussian; the bsdf strategy's variance, measured
// from a few hundred passes under a map with bright spots, is heavy-tailed); image means within
// 5 sigma of their summed variance.
#include "render_util.h"

#include <gtest/gtest.h>

namespace {

et::Scene scene(const et::EnvMap& env, const std::string& strategy, int depth, uint32_t seed) {
    et::Scene s = ett::base_scene(32, 32, env);
    s.materials.push_back(ett::diffuse(0.5f));
    s.materials.push_back(ett::diffuse(0.8f));
    et::Material plastic;
    plastic.type = ETK_MAT_MICROFACET;
    plastic.albedo = glm::vec3(0.3f);
    plastic.specular = glm::vec3(0.04f);
    plastic.roughness = 0.2f;
    s.materials.push_back(plastic);
    ett::add_square(s.triangles, glm::vec3(0.0f), glm::vec3(0, 1, 0), 4.0f, 0);
    ett::add_sphere(s.triangles, glm::vec3(-0.6f, 0.5f, 0.0f), 0.5f, 32, true, 1);
    ett::add_sphere(s.triangles, glm::vec3(0.6f, 0.5f, 0.0f), 0.5f, 32, true, 2);
    s.camera.eye = {0.0f, 1.2f, 3.2f};
    s.camera.target = {0.0f, 0.45f, 0.0f};
    s.camera.fov_deg = 40.0f;
    s.settings.strategy = et::parse_strategy(strategy, "test");
    s.settings.max_depth = depth;
    s.settings.seed = seed;
    return s;
}

void expect_agree(const ett::RenderResult& a, const ett::RenderResult& b, const std::string& what) {
    const ett::Agreement g = ett::agreement(a, b);
    std::printf("%-28s means %.5f / %.5f (z %.2f), mean z^2 %.3f, max |z| %.2f, |z|>4 %.4f\n",
                what.c_str(), g.mean_a, g.mean_b, g.mean_z, g.mean_z2, g.max_abs_z, g.frac_over_4);
    EXPECT_LE(std::fabs(g.mean_z), 5.0) << what;
    EXPECT_LE(g.mean_z2, 1.3) << what;
    EXPECT_LE(g.frac_over_4, 0.005) << what;
}

class Strategies : public ::testing::TestWithParam<int> {};

TEST_P(Strategies, ConvergeToTheSameImage) {
    ETT_DATA_FILE(path, "envmaps/pisa.hdr");
    const int depth = GetParam();
    const et::EnvMap env = et::load_envmap(path, {});
    const int spp = 256;
    const auto light = ett::render(scene(env, "light", depth, 1), "cpu", spp);
    const auto light2 = ett::render(scene(env, "light", depth, 2), "cpu", spp);
    const auto bsdf = ett::render(scene(env, "bsdf", depth, 3), "cpu", spp);
    const auto mis = ett::render(scene(env, "mis", depth, 4), "cpu", spp);
    // MIS compensation (with visible-normal GGX sampling, its default), and the paper's MIS with
    // visible-normal sampling alone.
    const auto comp = ett::render(scene(env, "compensated", depth, 5), "cpu", spp);
    et::Scene vndf_scene = scene(env, "mis", depth, 6);
    vndf_scene.settings.bsdf_sampling = et::BsdfSampling::vndf;
    const auto mis_vndf = ett::render(vndf_scene, "cpu", spp);
    // Light samples guided by learned visibility (tables from the first passes).
    const auto visibility = ett::render(scene(env, "visibility", depth, 10), "cpu", spp);
    // Light samples from the map times the cosine to the first vertex's normal bin.
    const auto cosine = ett::render(scene(env, "cosine", depth, 13), "cpu", spp);
    // Splitting: more light than BSDF samples per vertex, and the other way round (the
    // multi-sample MIS weights on the counts; the extra samples' lattice and lobe choice).
    et::Scene split_light = scene(env, "mis", depth, 11), split_bsdf = scene(env, "mis", depth, 12);
    split_light.settings.light_samples = 4;
    split_light.settings.bsdf_samples = 2;
    split_bsdf.settings.light_samples = 1;
    split_bsdf.settings.bsdf_samples = 8;
    const auto mis_split_light = ett::render(split_light, "cpu", spp);
    const auto mis_split_bsdf = ett::render(split_bsdf, "cpu", spp);
    const std::string d = " depth " + std::to_string(depth);
    // The noise estimate itself: two seeds of one strategy.
    const ett::Agreement self = ett::agreement(light, light2);
    EXPECT_GT(self.mean_z2, 0.8);
    expect_agree(light, light2, "light vs light (seed)" + d);
    expect_agree(light, bsdf, "light vs bsdf" + d);
    expect_agree(light, mis, "light vs mis" + d);
    expect_agree(bsdf, mis, "bsdf vs mis" + d);
    expect_agree(light, comp, "light vs compensated" + d);
    expect_agree(mis, comp, "mis vs compensated" + d);
    expect_agree(light, mis_vndf, "light vs mis+vndf" + d);
    expect_agree(mis, visibility, "mis vs visibility" + d);
    expect_agree(light, cosine, "light vs cosine" + d);
    expect_agree(light, mis_split_light, "light vs mis 4+2 samples" + d);
    expect_agree(bsdf, mis_split_bsdf, "bsdf vs mis 1+8 samples" + d);
}

// A white diffuse ceiling seen from below, lit only by the lower sky (radiance 1) of a map whose
// sun is 1e11 x brighter: 0.8 exactly, for every strategy that combines light and BSDF samples.
// A float CDF could not hold the widths of the rows after the sun's: the cosine strategy's
// tables took the rows' stored densities and drew directions the map's density calls
// impossible, and the image came out 9% dark (z ~ 50 here).
TEST(Strategies, AgreeUnderASunFarBrighterThanItsSky) {
    et::RgbImage sky = ett::constant_image(128, 64, 1.0f);
    for (int k = 0; k < 3; ++k)
        sky.rgb[3 * (16 * 128 + 40) + k] = 1e11f;
    const et::EnvMap env = et::make_envmap("sun", sky, {});
    for (const char* strategy : {"mis", "compensated", "cosine", "visibility"}) {
        et::Scene s = ett::base_scene(16, 16, env);
        s.materials.push_back(ett::diffuse(0.8f));
        ett::add_square(s.triangles, glm::vec3(0, 1, 0), glm::vec3(0, -1, 0), 4.0f, 0);
        s.camera.eye = {0.0f, 0.0f, 0.0f};
        s.camera.target = {0.0f, 1.0f, -0.2f};
        s.camera.up = {0.0f, 0.0f, -1.0f};
        s.camera.fov_deg = 30.0f;
        s.settings.strategy = et::parse_strategy(strategy, "test");
        s.settings.max_depth = 1;
        s.settings.seed = 3;
        const ett::RenderResult r = ett::render(s, "cpu", 128);
        double mean = 0.0, var = 0.0;
        for (size_t i = 0; i < r.mean.size(); ++i) {
            mean += r.mean[i];
            var += r.var_mean(i);
        }
        const double n = double(r.mean.size());
        mean /= n;
        const double sd = std::sqrt(var) / n;
        std::printf("%-12s mean %.6f, sd %.2g\n", strategy, mean, sd);
        // + 1e-4: the light samples that reach the lower sky (each row there keeps its least
        // share of the map's CDF, env_distribution.h) are too rare for the passes' variance to
        // show them: the MIS strategies' means sit 1e-5 .. 3e-5 low at this count.
        EXPECT_LE(std::fabs(mean - 0.8), 5.0 * sd + 1e-4) << strategy;
    }
}

// The compensated strategy samples the full map at the path's first vertex, where the sampler's
// stratification is best kept by its smooth warp (light_sampling.h), and the
// compensated distribution below it: at depth 1 it renders the bits of the paper's MIS with the
// compensated strategy's balance heuristic and visible-normal sampling, at depth 3 it does not.
// Both back ends (the light batches draw from the same distribution as the shade stage).
TEST(Strategies, CompensatedLeavesTheFirstVertexToTheFullMap) {
    ETT_DATA_FILE(path, "envmaps/pisa.hdr");
    const et::EnvMap env = et::load_envmap(path, {});
    for (const char* backend : {"cpu", "opencl"})
        for (int depth : {1, 3}) {
            et::Scene comp = scene(env, "compensated", depth, 5), mis = scene(env, "mis", depth, 5);
            mis.settings.heuristic = et::MisHeuristic::balance;
            mis.settings.bsdf_sampling = et::BsdfSampling::vndf;
            const auto a = ett::render(comp, backend, 8, false),
                       b = ett::render(mis, backend, 8, false);
            size_t differ = 0;
            for (size_t i = 0; i < a.mean.size(); ++i)
                differ += a.mean[i] != b.mean[i];
            if (depth == 1)
                EXPECT_EQ(differ, 0u) << backend << ": the first vertex's light samples differ";
            else
                EXPECT_GT(differ, a.mean.size() / 4) << backend << ": nothing compensated below";
        }
}

// The compensated strategy's last BSDF sample, taken with probability q below 1 where the map has
// black blocks (integrator.h, etk_last_bsdf_share), weighted on the counts (1, q) by the light
// sample, by the BSDF sample and at its miss. Under a map that is black nowhere those weights
// carry much of the image (glossy lobes, the compensated distribution's zeros below the mean),
// so the test forces the rule there: a mask with no black block and a lit solid angle of 0.5 sr
// (q = 0.16 on the diffuse surfaces). Any q in (0, 1] leaves the estimator unbiased: the image
// agrees with the light and mis strategies'. Fails when any of the three weights leaves q out.
TEST_P(Strategies, CompensatedWithFewLastBsdfSamplesConverges) {
    ETT_DATA_FILE(path, "envmaps/pisa.hdr");
    const int depth = GetParam(), spp = 256;
    const et::EnvMap env = et::load_envmap(path, {});
    const auto light = ett::render(scene(env, "light", depth, 21), "cpu", spp);
    const auto mis = ett::render(scene(env, "mis", depth, 22), "cpu", spp);
    const auto few =
        ett::render(scene(env, "compensated", depth, 23), "cpu", spp, true, [](et::DeviceScene& d) {
            d.params.env.black_w = d.params.env.black_h = 1;
            d.env_black = {0}; // one block, clear: nothing is black
            d.params.env.lit_sr = 0.5f;
        });
    const std::string d = " depth " + std::to_string(depth);
    expect_agree(light, few, "light vs compensated, q < 1" + d);
    expect_agree(mis, few, "mis vs compensated, q < 1" + d);
}

// An interior, where the visibility strategy's tables move light samples away from the map's
// distribution: a closed box lit through one opening (the open side's square is missing) and a
// block inside, seen from within.
et::Scene interior(const et::EnvMap& env, const std::string& strategy, uint32_t seed) {
    et::Scene s = ett::base_scene(32, 32, env);
    s.materials.push_back(ett::diffuse(0.7f));
    const float h = 1.0f; // half the side: a 2 x 2 x 2 room
    ett::add_square(s.triangles, glm::vec3(0, 0, 0), glm::vec3(0, 1, 0), h, 0);  // floor
    ett::add_square(s.triangles, glm::vec3(0, h, 0), glm::vec3(0, -1, 0), h, 0); // ceiling
    ett::add_square(s.triangles, glm::vec3(-1, 1, 0), glm::vec3(1, 0, 0), h, 0);
    ett::add_square(s.triangles, glm::vec3(1, 1, 0), glm::vec3(-1, 0, 0), h, 0);
    ett::add_square(s.triangles, glm::vec3(0, 1, 1), glm::vec3(0, 0, -1), h, 0); // back
    ett::add_square(s.triangles, glm::vec3(0, 0.3f, 0.2f), glm::vec3(0, 1, 0), 0.3f, 0);
    s.camera.eye = {0.0f, 1.0f, 0.9f};
    s.camera.target = {0.0f, 0.5f, -1.0f};
    s.camera.fov_deg = 80.0f;
    s.settings.strategy = et::parse_strategy(strategy, "test");
    s.settings.max_depth = 3;
    s.settings.seed = seed;
    return s;
}

// The learned strategy converges to the paper's image there.
TEST(Strategies, VisibilityConvergesInAnInterior) {
    ETT_DATA_FILE(path, "envmaps/pisa.hdr");
    const et::EnvMap env = et::load_envmap(path, {});
    const int spp = 256;
    const auto mis = ett::render(interior(env, "mis", 1), "cpu", spp);
    const auto mis2 = ett::render(interior(env, "mis", 2), "cpu", spp);
    // The tables throughout: on this 32 x 32 film 16 passes teach them too little for the
    // verdict (render/guide_verdict.h) to keep them, and the tables' estimator is the one tested.
    const auto visibility =
        ett::render(interior(env, "visibility", 3), "cpu", spp, true,
                    [](et::DeviceScene& d) { d.guide_options.verdict_passes = 0; });
    // Cells that face away from the opening learn to take fewer light samples (their light
    // comes back along the continuations): the estimator with counts below 1 is the one tested.
    uint64_t fewer = 0;
    for (const auto& [n, cells] : visibility.light_counts)
        fewer += n < 1.0f ? cells : 0;
    EXPECT_GT(fewer, 0u);
    EXPECT_GT(ett::agreement(mis, mis2).mean_z2, 0.8);
    expect_agree(mis, mis2, "interior: mis vs mis (seed)");
    expect_agree(mis, visibility, "interior: mis vs visibility");
}

// The auto strategy converges to the paper's image whichever its verdict: the tables after it
// (a verdict at no cost), or compensated for every pass after the verdict's (at a cost no error
// ratio reaches), its learning passes and its verdict's passes of the tables kept in the image.
TEST(Strategies, AutoConvergesWhicheverItsVerdict) {
    ETT_DATA_FILE(path, "envmaps/pisa.hdr");
    const et::EnvMap env = et::load_envmap(path, {});
    const int spp = 256;
    const auto mis = ett::render(interior(env, "mis", 1), "cpu", spp);
    for (const double cost : {0.0, 1e30}) {
        const auto automatic =
            ett::render(interior(env, "auto", 4), "cpu", spp, true, [cost](et::DeviceScene& d) {
                d.guide_options.verdict_cost = d.guide_options.verdict_cost_guided = cost;
            });
        EXPECT_EQ(automatic.verdict, cost > 0.0 ? "compensated" : "tables");
        expect_agree(mis, automatic, "interior: mis vs auto, verdict " + automatic.verdict);
    }
}

// The same with every learned cell taking 1/8 of a light sample, so that the light sample's
// count enters every weight that has a light density in it -- the light sample's own, and the
// escaped continuation's (etk_escaped): leaving it out of either biases the image.
TEST(Strategies, VisibilityWithFewLightSamplesConverges) {
    ETT_DATA_FILE(path, "envmaps/pisa.hdr");
    const et::EnvMap env = et::load_envmap(path, {});
    const int spp = 256;
    const auto mis = ett::render(interior(env, "mis", 1), "cpu", spp);
    const auto few =
        ett::render(interior(env, "visibility", 3), "cpu", spp, true, [](et::DeviceScene& d) {
            d.guide_options.light_counts.fill(0.125);
            d.guide_options.min_records = 1;
            d.guide_options.verdict_passes = 0; // the tables throughout (above)
        });
    uint64_t eighth = 0;
    for (const auto& [n, cells] : few.light_counts)
        eighth += n == 0.125f ? cells : 0;
    EXPECT_GT(eighth, 10u);
    expect_agree(mis, few, "interior: mis vs visibility with 1/8 light sample");
}

INSTANTIATE_TEST_SUITE_P(Depth, Strategies, ::testing::Values(1, 3));

// RMSE against a high-spp reference, for spp = 4 ... 128 (independent seeds): a log-log fit of
// slope -1/2. The reference's own noise (var / N_ref per pixel, measured) is subtracted from each
// mean squared error. Each MSE's standard error is measured from the spread of the per-pixel
// squared errors (sd / sqrt(pixels)); through d log RMSE = d MSE / (2 MSE) it weights a least
// squares fit whose slope has a standard error from those weights. The slope must be within 4
// of its standard errors (plus 0.01 for what the weights miss) of -0.5.
TEST(Strategies, RmseFallsAsOneOverSqrtSpp) {
    ETT_DATA_FILE(path, "envmaps/pisa.hdr");
    const et::EnvMap env = et::load_envmap(path, {});
    const int n_ref = 2048;
    const auto ref = ett::render(scene(env, "mis", 1, 100), "cpu", n_ref);
    double ref_noise = 0.0;
    for (size_t i = 0; i < ref.mean.size(); ++i)
        ref_noise += ref.var_mean(i) / ref.mean.size();
    std::vector<double> x, y, w;
    for (int spp = 4; spp <= 128; spp *= 2) {
        const auto r = ett::render(scene(env, "mis", 1, 200 + spp), "cpu", spp, false);
        const size_t n = r.mean.size();
        double m = 0.0, m2 = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const double e2 = std::pow(double(r.mean[i]) - ref.mean[i], 2);
            m += e2 / n;
            m2 += e2 * e2 / n;
        }
        const double se = std::sqrt(std::max(0.0, m2 - m * m) / n);
        const double mse = m - ref_noise;
        ASSERT_GT(mse, 4 * se) << "spp " << spp << ": error lost in the reference's noise";
        const double sd_log = 0.5 * se / mse;
        x.push_back(std::log(double(spp)));
        y.push_back(0.5 * std::log(mse));
        w.push_back(1.0 / (sd_log * sd_log));
        std::printf("spp %4d: RMSE %.5f (+- %.1f%%)\n", spp, std::sqrt(mse), 100 * sd_log);
    }
    double sw = 0, sx = 0, sy = 0;
    for (size_t i = 0; i < x.size(); ++i)
        sw += w[i], sx += w[i] * x[i], sy += w[i] * y[i];
    const double mx = sx / sw, my = sy / sw;
    double sxx = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        sxx += w[i] * (x[i] - mx) * (x[i] - mx);
        sxy += w[i] * (x[i] - mx) * (y[i] - my);
    }
    const double slope = sxy / sxx, se_slope = std::sqrt(1.0 / sxx);
    std::printf("log-log slope %.4f +- %.4f (reference %d spp)\n", slope, se_slope, n_ref);
    EXPECT_NEAR(slope, -0.5, 4 * se_slope + 0.01);
}

} // namespace
