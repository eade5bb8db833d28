// The lat-long parameterisation (kernels/latlong.h), the map rotation and the bilinear radiance
// lookup (kernels/envmap.h) against the convention of ../shared/data/README.md.
#include "load/environment_map.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using etk::float2;
using etk::float3;

void expect_dir(float3 d, float x, float y, float z) {
    EXPECT_NEAR(d.x, x, 1e-6f);
    EXPECT_NEAR(d.y, y, 1e-6f);
    EXPECT_NEAR(d.z, z, 1e-6f);
}

TEST(LatLong, ConventionOfTheSharedData) {
    // Row 0 looks up, the centre looks along -Z, u grows towards +X.
    expect_dir(etk::etk_latlong_to_dir(etk::make_float2(0.3f, 0.0f)), 0, 1, 0);
    expect_dir(etk::etk_latlong_to_dir(etk::make_float2(0.3f, 1.0f)), 0, -1, 0);
    expect_dir(etk::etk_latlong_to_dir(etk::make_float2(0.5f, 0.5f)), 0, 0, -1);
    expect_dir(etk::etk_latlong_to_dir(etk::make_float2(0.75f, 0.5f)), 1, 0, 0);
    expect_dir(etk::etk_latlong_to_dir(etk::make_float2(0.25f, 0.5f)), -1, 0, 0);
    expect_dir(etk::etk_latlong_to_dir(etk::make_float2(0.0f, 0.5f)), 0, 0, 1);
}

TEST(LatLong, RoundTripAgainstReadmeFormula) {
    std::mt19937 rng(3);
    std::normal_distribution<double> g;
    for (int i = 0; i < 100000; ++i) {
        double x = g(rng), y = g(rng), z = g(rng), len = std::sqrt(x * x + y * y + z * z);
        x /= len, y /= len, z /= len;
        // docs/conventions.md: u = (1 + atan2(x, -z) / pi) / 2, v = acos(y) / pi, in double.
        const double u = 0.5 * (1.0 + std::atan2(x, -z) / M_PI), v = std::acos(y) / M_PI;
        const float2 uv = etk::etk_dir_to_latlong(etk::make_float3(float(x), float(y), float(z)));
        ASSERT_NEAR(uv.y, v, 2e-6);
        // Rounding the input to float moves theta by up to ~ulp(1) / sin(theta) near the poles.
        const double st = std::max(std::sin(M_PI * v), 1e-7);
        if (st > 1e-3) { // u is meaningless at the poles
            ASSERT_NEAR(std::fmod(uv.x - u + 1.5, 1.0) - 0.5, 0.0, 2e-6 / st);
        }
        const float3 d = etk::etk_latlong_to_dir(uv);
        const double tol = 4e-6 + 2e-7 / st;
        ASSERT_NEAR(etk::length(d), 1.0f, 2e-6f);
        ASSERT_NEAR(d.x, x, tol);
        ASSERT_NEAR(d.y, y, tol);
        ASSERT_NEAR(d.z, z, tol);
    }
}

TEST(LatLong, SolidAngleConversionAtAndNearThePoles) {
    // |J| = 2 pi^2 sin(theta); zero density at the poles, never Inf or NaN.
    EXPECT_EQ(etk::etk_latlong_pdf_to_solid_angle(3.0f, 0.0f), 0.0f);
    EXPECT_EQ(etk::etk_latlong_pdf_to_solid_angle(3.0f, 1.0f), 0.0f);
    EXPECT_EQ(etk::etk_latlong_sin_theta(0.0f), 0.0f);
    EXPECT_EQ(etk::etk_latlong_sin_theta(1.0f), 0.0f);
    for (float v : {0.5f, 0.25f, 0.01f, 0.99f, 1e-7f, 1.0f - 6e-8f}) {
        const float p = etk::etk_latlong_pdf_to_solid_angle(1.0f, v);
        ASSERT_TRUE(std::isfinite(p)) << v;
        EXPECT_NEAR(p, 1.0 / (2 * M_PI * M_PI * std::sin(M_PI * double(v))), 1e-5 * p) << v;
    }
}

TEST(LatLong, RotationIsAboutTheUpAxisAndInvertible) {
    et::EnvMap env;
    env.image = ett::constant_image(4, 2, 1.0f);
    for (float deg : {0.0f, 30.0f, 90.0f, -135.0f, 400.0f}) {
        env.rotation_degrees = deg;
        const etk::EtkEnvMap desc = env.desc();
        std::mt19937 rng(5);
        std::normal_distribution<float> g;
        for (int i = 0; i < 1000; ++i) {
            const float3 d = etk::normalize(etk::make_float3(g(rng), g(rng), g(rng)));
            const float3 w = etk::etk_env_to_world(desc, d);
            EXPECT_FLOAT_EQ(w.y, d.y);
            EXPECT_NEAR(etk::length(w), 1.0f, 1e-6f);
            const float3 back = etk::etk_world_to_env(desc, w);
            ASSERT_NEAR(back.x, d.x, 1e-6f);
            ASSERT_NEAR(back.z, d.z, 1e-6f);
        }
        // A rotation by `deg` turns the horizon by that angle.
        const float3 c = etk::etk_env_to_world(desc, etk::make_float3(0, 0, -1));
        EXPECT_NEAR(std::acos(std::clamp(-c.z, -1.0f, 1.0f)) * 180.0 / M_PI,
                    std::fabs(std::remainder(deg, 360.0f)), 1e-3);
    }
}

TEST(LatLong, BilinearLookupHitsTexelCentresWrapsAndClamps) {
    const int w = 8, h = 4;
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                img.at(x, y)[c] = float(1 + x + 10 * y + 100 * c);
    const float* t = img.rgb.data();
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float3 v =
                etk::etk_env_lookup_uv(t, w, h, etk::make_float2((x + 0.5f) / w, (y + 0.5f) / h));
            EXPECT_FLOAT_EQ(v.x, img.at(x, y)[0]) << x << "," << y;
            EXPECT_FLOAT_EQ(v.y, img.at(x, y)[1]);
            EXPECT_FLOAT_EQ(v.z, img.at(x, y)[2]);
        }
    // u = 0 is halfway between the last and the first column (wrap in phi).
    const float3 seam = etk::etk_env_lookup_uv(t, w, h, etk::make_float2(0.0f, 1.5f / h));
    EXPECT_FLOAT_EQ(seam.x, 0.5f * (img.at(0, 1)[0] + img.at(w - 1, 1)[0]));
    // Above the first row's centre only the first row counts (clamp at the pole).
    const float3 top = etk::etk_env_lookup_uv(t, w, h, etk::make_float2(2.5f / w, 0.0f));
    EXPECT_FLOAT_EQ(top.x, img.at(2, 0)[0]);
    const float3 bottom = etk::etk_env_lookup_uv(t, w, h, etk::make_float2(2.5f / w, 1.0f));
    EXPECT_FLOAT_EQ(bottom.x, img.at(2, h - 1)[0]);
    // Halfway between two texel centres: the mean.
    const float3 mid = etk::etk_env_lookup_uv(t, w, h, etk::make_float2(3.0f / w, 1.5f / h));
    EXPECT_FLOAT_EQ(mid.x, 0.5f * (img.at(2, 1)[0] + img.at(3, 1)[0]));
    // u = 1 wraps like u = 0; u outside [0, 1] (the remainder's path) like u shifted into it.
    for (float u : {0.0f, 0.03125f, 0.25f, 0.96875f}) {
        const float3 a = etk::etk_env_lookup_uv(t, w, h, etk::make_float2(u, 1.5f / h));
        for (float shift : {1.0f, -1.0f, 2.0f, -3.0f}) {
            const float3 b = etk::etk_env_lookup_uv(t, w, h, etk::make_float2(u + shift, 1.5f / h));
            EXPECT_EQ(a.x, b.x) << "u " << u << " shift " << shift;
        }
    }
}

TEST(LatLong, RadianceFollowsRotation) {
    et::RgbImage img = ett::constant_image(16, 8, 0.0f);
    img.at(12, 4)[0] = 5.0f; // one texel on the horizon, towards +X
    et::EnvMap env = et::make_envmap("spot", img, {});
    env.rotation_degrees = 57.0f;
    const etk::EtkEnvMap desc = env.desc();
    const float2 uv = etk::make_float2(12.5f / 16, 4.5f / 8);
    const float3 world = etk::etk_env_to_world(desc, etk::etk_latlong_to_dir(uv));
    EXPECT_NEAR(etk::etk_env_radiance(img.rgb.data(), desc, world).x, 5.0f, 1e-4f);
    EXPECT_GT(etk::etk_env_pdf(env.dist.table.data(), desc, world), 0.0f);
}

} // namespace
