// The map's black mask (host/lib/prepare/env_black_mask.h, kernels/envmap.h etk_env_black_uv):
// wherever it says black, the renderer's bilinear radiance lookup must read zero -- or the last
// bounce would skip light (a biased image). Checked at random and at block-edge coordinates on
// maps whose lit texels sit at block edges, the longitude seam and the poles, for sizes that are
// and are not multiples of the block; and the mask must say black for most of a map with one lit
// texel (else it saves nothing).
#include "prepare/env_black_mask.h"
#include "kernels/envmap.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

etk::EtkEnvMap desc_of(const et::RgbImage& img, const et::EnvBlackMask& m) {
    etk::EtkEnvMap d{};
    d.tex_w = img.width;
    d.tex_h = img.height;
    d.scale = 1.0f;
    d.black_w = m.width;
    d.black_h = m.height;
    return d;
}

void light(et::RgbImage& img, int x, int y, int channel) {
    img.at(x, y)[channel] = 1.0f;
}

// Fraction of the probed coordinates the mask calls black; fails the test where a black one reads
// light.
double check_sound(const et::RgbImage& img) {
    const et::EnvBlackMask m = et::env_black_mask(img);
    if (m.width == 0)
        return 0.0;
    const etk::EtkEnvMap d = desc_of(img, m);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<etk::float2> uvs;
    for (int i = 0; i < 200000; ++i)
        uvs.push_back(etk::make_float2(U(rng), U(rng)));
    // Texel and block edges, just inside and outside, and the ends of the range.
    for (int x = 0; x <= img.width; ++x)
        for (int y = 0; y <= img.height; y += 3)
            for (float e : {-1e-4f, 0.0f, 1e-4f, 0.5f})
                uvs.push_back(etk::make_float2(std::min(1.0f, std::max(0.0f, (x + e) / img.width)),
                                               std::min(1.0f, (y + 0.5f) / img.height)));
    for (int y = 0; y <= img.height; ++y)
        for (float e : {-1e-4f, 0.0f, 1e-4f})
            uvs.push_back(
                etk::make_float2(0.3f, std::min(1.0f, std::max(0.0f, (y + e) / img.height))));
    size_t black = 0;
    for (const etk::float2& uv : uvs) {
        if (!etk::etk_env_black_uv(m.bits.data(), d, uv))
            continue;
        ++black;
        const etk::float3 L = etk::etk_env_radiance_uv(img.rgb.data(), d, uv);
        EXPECT_TRUE(L.x == 0.0f && L.y == 0.0f && L.z == 0.0f)
            << img.width << "x" << img.height << " map: black by the mask at (" << uv.x << ", "
            << uv.y << ") but reads " << L.x << " " << L.y << " " << L.z;
        if (::testing::Test::HasFailure())
            break;
    }
    return double(black) / uvs.size();
}

TEST(EnvBlackMask, BlackOnlyWhereTheLookupReadsZero) {
    for (auto [w, h] : {std::pair{64, 32}, {61, 29}, {128, 64}, {16, 8}, {9, 5}}) {
        et::RgbImage img = ett::constant_image(w, h, 0.0f);
        // On block edges (columns 7, 8 and 23; rows 8, 15), the seam (0, w - 1) and the poles.
        light(img, 7, 3, 0);
        light(img, 8 % w, 8 % h, 1);
        light(img, 23 % w, 15 % h, 2);
        light(img, w - 1, h / 2, 0);
        light(img, w / 2, 0, 1);
        light(img, w / 3, h - 1, 2);
        check_sound(img);
    }
    // A lit texel at column 0 only: the blocks at the far end of the rows neighbour it.
    et::RgbImage seam = ett::constant_image(64, 32, 0.0f);
    light(seam, 0, 16, 0);
    check_sound(seam);
}

TEST(EnvBlackMask, MostOfAOneTexelMapIsBlack) {
    et::RgbImage img = ett::constant_image(256, 128, 0.0f);
    light(img, 100, 40, 1);
    const double black = check_sound(img);
    EXPECT_GT(black, 0.95); // all but the lit block and its neighbours: 9 of 512 blocks
    // A map with no black block has no mask; an all-black one is black everywhere.
    EXPECT_EQ(et::env_black_mask(ett::constant_image(64, 32, 0.5f)).width, 0);
    EXPECT_GT(check_sound(ett::constant_image(64, 32, 0.0f)), 0.999);
}

// The solid angle of the directions the mask leaves clear (lit_solid_angle, which bounds the
// compensated strategy's last BSDF samples): the sum over a grid of 4 x 4 cells per texel -- each
// inside one block, so its bit is the kernel's reading at its centre -- of the cells' exact solid
// angles, for sizes with partial blocks, a lit pole and the seam. 4 pi without a mask; 0 for a
// black map.
TEST(EnvBlackMask, LitSolidAngleIsWhereTheMaskSaysNotBlack) {
    for (auto [w, h] : {std::pair{64, 32}, {61, 29}, {128, 64}}) {
        et::RgbImage img = ett::constant_image(w, h, 0.0f);
        light(img, 7, 3, 0);
        light(img, w - 1, h / 2, 1);
        light(img, w / 3, h - 1, 2);
        const et::EnvBlackMask m = et::env_black_mask(img);
        ASSERT_GT(m.width, 0) << w << "x" << h;
        const etk::EtkEnvMap d = desc_of(img, m);
        const int gw = 4 * w, gh = 4 * h;
        double clear = 0.0;
        for (int y = 0; y < gh; ++y) {
            const double band =
                2.0 * M_PI / gw * (std::cos(M_PI * y / gh) - std::cos(M_PI * (y + 1) / gh));
            for (int x = 0; x < gw; ++x)
                if (!etk::etk_env_black_uv(m.bits.data(), d,
                                           etk::make_float2((x + 0.5f) / gw, (y + 0.5f) / gh)))
                    clear += band;
        }
        EXPECT_NEAR(m.lit_solid_angle, clear, 1e-5 * 4.0 * M_PI) << w << "x" << h;
        EXPECT_LT(m.lit_solid_angle, 0.9 * 4.0 * M_PI) << w << "x" << h;
    }
    EXPECT_NEAR(et::env_black_mask(ett::constant_image(64, 32, 0.5f)).lit_solid_angle, 4.0 * M_PI,
                1e-5);
    EXPECT_EQ(et::env_black_mask(ett::constant_image(64, 32, 0.0f)).lit_solid_angle, 0.0f);
}

} // namespace
