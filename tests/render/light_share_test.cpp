// The adaptive strategy's learner (host/lib/render/light_share.h) on films whose per-candidate
// variance is known, and the renderer's learning: deterministic, independent of threads, and the
// same when a render starts past the learning passes (a resume).
#include "render/light_share.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <random>

namespace {

using et::float4;

// The learning passes of a 64x64 film, every pixel in bin 3 with mean 1; candidate k's pixels
// have standard deviation sd[k]. Pixels of bin 5 have too few pixels to be compared.
et::LightShareLearner learn(const std::array<double, ETK_SHARE_CANDIDATES>& sd, uint32_t seed) {
    const int w = 64, h = 64;
    et::LightShareOptions o;
    et::LightShareLearner L(o, w, h, seed);
    std::mt19937 rng(seed);
    std::normal_distribution<double> z(0.0, 1.0);
    for (int pass = 0; pass < o.learning_passes; ++pass) {
        std::vector<float4> film(static_cast<size_t>(w) * h); // the pass: one sample per pixel
        L.begin_pass();
        int* bins = L.bins_of_pass();
        for (int px = 0; px < w * h; ++px) {
            const int k = etk::etk_learning_candidate(seed, px);
            const float x = static_cast<float>(1.0 + sd[k] * z(rng));
            film[px] = float4{x, x, x, 1.0f};
            bins[px] = px < 20 ? 5 : 3;
        }
        L.end_pass(film);
    }
    return L;
}

TEST(LightShare, MeasuresEachCandidatesVariance) {
    const std::array<double, ETK_SHARE_CANDIDATES> sd = {0.2, 0.15, 0.1, 0.05};
    const et::LightShareLearner L = learn(sd, 7);
    const auto cells = L.measure();
    for (int k = 0; k < ETK_SHARE_CANDIDATES; ++k) {
        const auto& c = cells[3][k];
        ASSERT_GT(c.pixels, 1000u);
        // Weighted by 1 / (m^2 + eps), m the pixel's mean over the other passes (1 +- sd / 2.8,
        // so E[1 / m^2] ~ 1 + sd^2 / 2.6, at most 2%): the estimate is the variance of a block
        // mean (independent samples: sd^2 / block), within 4 standard errors (sqrt(2 / pairs))
        // and that 2%.
        const double est = c.sum / double(c.pixels);
        const double v = sd[k] * sd[k] / et::LightShareOptions{}.block;
        EXPECT_NEAR(est, v, v * (0.02 + 4.0 * std::sqrt(2.0 / double(c.pixels))))
            << "candidate " << k;
    }
}

TEST(LightShare, PicksTheCandidateOfLeastVariance) {
    for (int best = 0; best < ETK_SHARE_CANDIDATES; ++best) {
        std::array<double, ETK_SHARE_CANDIDATES> sd;
        sd.fill(0.5);
        sd[best] = 0.25;
        const auto choice = learn(sd, 11 + best).choices();
        EXPECT_EQ(choice[3], best);
        // Bins without enough pixels, or none, keep the default.
        EXPECT_EQ(choice[5], et::LightShareLearner::kDefaultCandidate);
        EXPECT_EQ(choice[0], et::LightShareLearner::kDefaultCandidate);
    }
}

TEST(LightShare, PairsWhoseFirstHitsDifferAreSkipped) {
    et::LightShareOptions o;
    et::LightShareLearner L(o, 8, 8, 1);
    for (int pass = 0; pass < o.learning_passes; ++pass) {
        std::vector<float4> film(64, float4{float(pass), 0, 0, 1.0f});
        L.begin_pass();
        for (int px = 0; px < 64; ++px)
            L.bins_of_pass()[px] = pass % 2; // never the same bin throughout a block
        L.end_pass(film);
    }
    for (const auto& bin : L.measure())
        for (const auto& c : bin)
            EXPECT_EQ(c.pixels, 0u);
}

et::Scene glossy_scene(uint32_t seed) {
    et::Scene s =
        ett::base_scene(24, 16, et::make_envmap("sky", ett::constant_image(32, 16, 1.0f), {}));
    s.camera.eye = {0, 1.2f, 3.0f};
    s.camera.target = {0, 0.4f, 0};
    s.materials.push_back(ett::diffuse(0.5f));
    et::Material metal;
    metal.type = ETK_MAT_MICROFACET;
    metal.specular = glm::vec3(0.9f);
    metal.roughness = 0.05f;
    s.materials.push_back(metal);
    ett::add_square(s.triangles, glm::vec3(0.0f), glm::vec3(0, 1, 0), 4.0f, 0);
    ett::add_sphere(s.triangles, glm::vec3(0, 0.5f, 0), 0.5f, 24, true, 1);
    s.settings.strategy = et::Strategy::adaptive;
    s.settings.backend = et::Backend::cpu;
    s.settings.max_depth = 1;
    s.settings.seed = seed;
    return s;
}

std::vector<float> render(const et::Scene& s, int threads, int from, int to,
                          const et::FilmSums* resume = nullptr,
                          std::array<int, ETK_SHARE_BINS>* choices = nullptr) {
    const ett::SampleRun run = ett::render_samples(s, threads, from, to, resume);
    if (choices)
        *choices = run.renderer->choices();
    std::vector<float> out = run.renderer->sums().mean();
    const std::vector<float> var = run.renderer->sums().variance_of_mean();
    out.insert(out.end(), var.begin(), var.end());
    return out;
}

TEST(LightShare, RendererLearnsDeterministicallyOnAnyThreadCount) {
    const et::Scene s = glossy_scene(3);
    std::array<int, ETK_SHARE_BINS> one{}, two{};
    const auto a = render(s, 1, 0, 20, nullptr, &one);
    const auto b = render(s, 2, 0, 20, nullptr, &two);
    EXPECT_EQ(a, b);
    EXPECT_EQ(one, two);
    for (int b = 0; b < 2; ++b) // the ground and the metal chose a candidate
        EXPECT_TRUE(one[b] >= 0 && one[b] < ETK_SHARE_CANDIDATES) << one[b];
}

TEST(LightShare, ResumedRenderLearnsTheSameShares) {
    const et::Scene s = glossy_scene(4);
    std::array<int, ETK_SHARE_BINS> whole{}, resumed{};
    const auto full = render(s, 2, 0, 20, nullptr, &whole);
    // The first 6 samples, then a new renderer resumes their film at sample 6: it renders the
    // learning passes on a scratch film, and the rest is bit-identical.
    const et::FilmSums part = ett::render_samples(s, 2, 0, 6).renderer->sums();
    const auto second = render(s, 2, 6, 20, &part, &resumed);
    EXPECT_EQ(full, second);
    EXPECT_EQ(whole, resumed);
}

} // namespace
