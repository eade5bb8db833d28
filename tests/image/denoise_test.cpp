// The denoiser (image/denoise.h) on synthetic images: a piecewise-smooth image with fixed-seed
// noise comes out closer to the clean one, with clean guides and with noisy guides prefiltered;
// non-finite input stays out of the output; mismatched images are refused by name. The tests that
// need Open Image Denoise skip where it is not installed (tools/setup installs it).
#include "image/denoise.h"
#include "image/image_metrics.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

namespace {

#define SKIP_WITHOUT_DENOISER()                                                                    \
    do {                                                                                           \
        const std::string why = ett::error_of([] { et::check_denoiser(); });                       \
        if (!why.empty())                                                                          \
            GTEST_SKIP() << why;                                                                   \
    } while (0)

constexpr int kW = 64, kH = 48;

// Two materials split by a diagonal edge, lit by a smooth gradient: what a render of two surfaces
// looks like, with the edge as the detail a denoiser must keep.
struct Scene {
    et::RgbImage beauty{kW, kH, std::vector<float>(kW* kH * 3)};
    et::RgbImage albedo{kW, kH, std::vector<float>(kW* kH * 3)};
    et::RgbImage normal{kW, kH, std::vector<float>(kW* kH * 3)};
};

Scene clean_scene() {
    Scene s;
    const float colour[2][3] = {{0.8f, 0.3f, 0.2f}, {0.2f, 0.5f, 0.7f}};
    const float facing[2][3] = {{0.0f, 0.0f, 1.0f}, {0.6f, 0.0f, 0.8f}};
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const int side = x + y > (kW + kH) / 2 ? 1 : 0;
            const float light = 0.5f + 1.5f * float(x) / kW;
            for (int c = 0; c < 3; ++c) {
                s.albedo.at(x, y)[c] = colour[side][c];
                s.normal.at(x, y)[c] = facing[side][c];
                s.beauty.at(x, y)[c] = colour[side][c] * light;
            }
        }
    return s;
}

// Monte Carlo-like noise: each value times (1 + 0.5 g), g standard normal, fixed seed.
et::RgbImage noisy(const et::RgbImage& clean, uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.0f, 1.0f);
    et::RgbImage out = clean;
    for (float& v : out.rgb)
        v = std::max(0.0f, v * (1.0f + 0.5f * g(rng)));
    return out;
}

double rel_mse(const et::RgbImage& a, const et::RgbImage& b) {
    return et::compare_images(a, b).rel_mse;
}

TEST(Denoise, BringsANoisyImageCloserToTheCleanOne) {
    SKIP_WITHOUT_DENOISER();
    const Scene s = clean_scene();
    const et::RgbImage input = noisy(s.beauty, 1);
    const et::RgbImage out = et::denoise(input, s.albedo, s.normal);
    ASSERT_EQ(out.width, kW);
    ASSERT_EQ(out.height, kH);
    const double before = rel_mse(input, s.beauty), after = rel_mse(out, s.beauty);
    // The noise's relative MSE is ~0.25; a denoiser that keeps the edge removes most of it.
    EXPECT_LT(after, 0.25 * before) << "noisy " << before << ", denoised " << after;
}

// Guides averaged over noisy samples are denoised first (cleanAux): the result is still close.
TEST(Denoise, PrefiltersNoisyGuides) {
    SKIP_WITHOUT_DENOISER();
    const Scene s = clean_scene();
    const et::RgbImage input = noisy(s.beauty, 2);
    const et::RgbImage albedo = noisy(s.albedo, 3), normal = noisy(s.normal, 4);
    const double before = rel_mse(input, s.beauty);
    const double prefiltered = rel_mse(et::denoise(input, albedo, normal), s.beauty);
    EXPECT_LT(prefiltered, 0.25 * before) << "noisy " << before << ", denoised " << prefiltered;
    const double beauty_only = rel_mse(et::denoise(input, {}, {}), s.beauty);
    EXPECT_LT(beauty_only, before);
}

TEST(Denoise, NonFiniteInputIsDenoisedAsZero) {
    SKIP_WITHOUT_DENOISER();
    const Scene s = clean_scene();
    et::RgbImage input = noisy(s.beauty, 5);
    input.at(10, 10)[0] = std::nanf("");
    input.at(20, 30)[1] = INFINITY;
    const et::RgbImage out = et::denoise(input, s.albedo, s.normal);
    for (float v : out.rgb)
        ASSERT_TRUE(std::isfinite(v));
}

TEST(Denoise, MismatchedImagesAreRefused) {
    const Scene s = clean_scene();
    const et::RgbImage small{8, 8, std::vector<float>(8 * 8 * 3, 0.5f)};
    EXPECT_NE(ett::error_of([&] { et::denoise(s.beauty, small, {}); }).find("albedo is 8x8"),
              std::string::npos);
    EXPECT_NE(ett::error_of([&] { et::denoise(s.beauty, s.albedo, small); }).find("normal"),
              std::string::npos);
    EXPECT_NE(ett::error_of([&] { et::denoise(s.beauty, {}, s.normal); }).find("needs an albedo"),
              std::string::npos);
    EXPECT_NE(ett::error_of([&] { et::denoise(et::RgbImage{}, {}, {}); }).find("non-empty"),
              std::string::npos);
}

} // namespace
