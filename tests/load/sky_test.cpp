// host/lib/load/sky: the procedural sun and sky. The sun sits where sun_elevation/sun_azimuth put
// it in the lat-long convention of kernels/latlong.h, its disc has the solid angle of
// sun_angular_radius, the map has the requested size and only finite non-negative texels, and
// the sky and ground scale with their parameters.
#include "load/sky.h"
#include "load/env_distribution.h"
#include "kernels/latlong.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace {

constexpr double kDeg = M_PI / 180.0;

etk::float3 sun_direction(float el_deg, float az_deg) {
    const double el = el_deg * kDeg, az = az_deg * kDeg;
    // Elevation above the horizon (y up), azimuth from -Z towards +X.
    return etk::make_float3(float(std::cos(el) * std::sin(az)), float(std::sin(el)),
                            float(-std::cos(el) * std::cos(az)));
}

etk::float3 texel_direction(const et::RgbImage& img, int x, int y) {
    return etk::etk_latlong_to_dir(
        etk::make_float2((x + 0.5f) / img.width, (y + 0.5f) / img.height));
}

double angle_deg(etk::float3 a, etk::float3 b) {
    const double c =
        std::clamp(double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z, -1.0, 1.0);
    return std::acos(c) / kDeg;
}

// Solid angle of texel row y.
double texel_solid_angle(const et::RgbImage& img, int y) {
    return 2.0 * M_PI / img.width *
           (std::cos(M_PI * y / img.height) - std::cos(M_PI * (y + 1) / img.height));
}

struct Brightest {
    int x = 0, y = 0;
    float lum = -1.0f;
};
Brightest brightest(const et::RgbImage& img) {
    Brightest b;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if (et::luminance(img.at(x, y)) > b.lum)
                b = {x, y, et::luminance(img.at(x, y))};
    return b;
}

// Direction of the disc's centroid: texels weighted by solid angle and luminance above `floor`.
etk::float3 centroid(const et::RgbImage& img, float floor) {
    double s[3] = {0, 0, 0};
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const double l = et::luminance(img.at(x, y)) - floor;
            if (l <= 0.0)
                continue;
            const etk::float3 d = texel_direction(img, x, y);
            const double wgt = l * texel_solid_angle(img, y);
            s[0] += wgt * d.x, s[1] += wgt * d.y, s[2] += wgt * d.z;
        }
    const double n = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    return etk::make_float3(float(s[0] / n), float(s[1] / n), float(s[2] / n));
}

TEST(Sky, SunIsWhereElevationAndAzimuthSay) {
    struct Case {
        float el, az;
    };
    for (const Case& k :
         {Case{35, 40}, Case{10, -120}, Case{60, 200}, Case{3, 0}, Case{45, 90}, Case{20, 179}}) {
        SCOPED_TRACE("elevation " + std::to_string(k.el) + " azimuth " + std::to_string(k.az));
        et::SkyParams p;
        p.width = 256;
        p.height = 128;
        p.sun_elevation_deg = k.el;
        p.sun_azimuth_deg = k.az;
        p.sun_angular_radius_deg = 1.5f;
        const et::RgbImage img = make_sky(p);
        const double texel = 180.0 / p.height;
        const etk::float3 sun = sun_direction(k.el, k.az);

        const Brightest b = brightest(img);
        EXPECT_LT(angle_deg(texel_direction(img, b.x, b.y), sun),
                  p.sun_angular_radius_deg + 1.5 * texel);
        // In texel coordinates: u = 1/2 + azimuth / 360 (mod 1), v = 1/2 - elevation / 180.
        const double u = std::fmod(0.5 + k.az / 360.0 + 1.0, 1.0), v = 0.5 - k.el / 180.0;
        double dx = std::fabs((b.x + 0.5) - u * p.width);
        dx = std::min(dx, p.width - dx);
        EXPECT_LE(dx, 2.5) << "column " << b.x;
        EXPECT_LE(std::fabs((b.y + 0.5) - v * p.height), 2.5) << "row " << b.y;
        // The disc's centroid is the sun direction to well within a texel.
        EXPECT_LT(angle_deg(centroid(img, 0.5f * b.lum), sun), 0.5 * texel);
    }
}

TEST(Sky, DefaultSunPosition) {
    const et::SkyParams p; // 1024 x 512, elevation 35, azimuth 40
    const et::RgbImage img = make_sky(p);
    const Brightest b = brightest(img);
    const double texel = 180.0 / p.height;
    const etk::float3 sun = sun_direction(p.sun_elevation_deg, p.sun_azimuth_deg);
    EXPECT_LT(angle_deg(texel_direction(img, b.x, b.y), sun),
              p.sun_angular_radius_deg + 1.5 * texel);
    EXPECT_LT(angle_deg(centroid(img, 0.5f * b.lum), sun), 0.5 * texel);
    // The sun outshines everything else by orders of magnitude.
    float sky_max = 0.0f;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if (angle_deg(texel_direction(img, x, y), sun) > 5.0)
                sky_max = std::max(sky_max, et::luminance(img.at(x, y)));
    EXPECT_GT(b.lum, 100.0f * sky_max);
}

TEST(Sky, SunSolidAngleMatchesItsRadius) {
    struct Case {
        int w, h;
        float radius;
    };
    for (const Case& k : {Case{1024, 512, 0.8f}, Case{512, 256, 2.0f}, Case{256, 128, 5.0f}}) {
        SCOPED_TRACE("radius " + std::to_string(k.radius) + " at " + std::to_string(k.w));
        et::SkyParams p;
        p.width = k.w;
        p.height = k.h;
        p.sun_angular_radius_deg = k.radius;
        p.sky_radiance = 0.0f; // the sun alone
        p.ground_albedo = 0.0f;
        const et::RgbImage img = make_sky(p);
        // Texels wholly inside the disc carry the sun's radiance times its colour.
        const Brightest b = brightest(img);
        EXPECT_FLOAT_EQ(img.at(b.x, b.y)[0], p.sun_radiance);
        EXPECT_FLOAT_EQ(img.at(b.x, b.y)[1], 0.93f * p.sun_radiance);
        EXPECT_FLOAT_EQ(img.at(b.x, b.y)[2], 0.82f * p.sun_radiance);
        double omega = 0.0;
        const etk::float3 sun = sun_direction(p.sun_elevation_deg, p.sun_azimuth_deg);
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const float* t = img.at(x, y);
                if (t[0] == 0.0f)
                    continue;
                // Nothing but the disc (and its partly covered rim) is lit.
                ASSERT_LT(angle_deg(texel_direction(img, x, y), sun), k.radius + 180.0 / k.h * 1.5)
                    << x << "," << y;
                omega += t[0] / p.sun_radiance * texel_solid_angle(img, y);
            }
        const double want = 2.0 * M_PI * (1.0 - std::cos(k.radius * kDeg));
        EXPECT_NEAR(omega / want, 1.0, 0.03);
    }
}

// The disc's power (radiance x solid angle) at any radius: a disc narrower than a texel, or
// than a texel's sub-samples, is still there with its whole power; a disc below the horizon is
// hidden by the ground, one on it keeps the half above.
TEST(Sky, SunPowerHoldsAtAnyRadiusAndTheGroundHidesIt) {
    struct Case {
        int w, h;
        float radius, elevation;
        double above; // the share of the disc above the horizon
    };
    for (const Case& k : {Case{1024, 512, 0.001f, 30, 1}, Case{1024, 512, 0.01f, 30, 1},
                          Case{1024, 512, 0.03f, 30, 1}, Case{1024, 512, 0.05f, 47, 1},
                          Case{1024, 512, 0.1f, 30, 1}, Case{256, 128, 0.3f, 12, 1},
                          Case{256, 128, 1.0f, 60, 1}, Case{64, 32, 0.02f, 89.99f, 1},
                          Case{1024, 512, 0.05f, 0, 0.5}, Case{256, 128, 0.5f, 0, 0.5},
                          Case{1024, 512, 0.05f, -1, 0}, Case{256, 128, 3.0f, -10, 0}}) {
        SCOPED_TRACE("radius " + std::to_string(k.radius) + " elevation " +
                     std::to_string(k.elevation) + " at " + std::to_string(k.w));
        et::SkyParams p;
        p.width = k.w;
        p.height = k.h;
        p.sun_angular_radius_deg = k.radius;
        p.sun_elevation_deg = k.elevation;
        p.sun_radiance = 1e6f;
        p.sky_radiance = 0.0f; // the sun alone
        p.ground_albedo = 0.0f;
        const et::RgbImage img = make_sky(p);
        double power = 0.0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x)
                power += double(img.at(x, y)[0]) * texel_solid_angle(img, y);
        const double want =
            p.sun_radiance * 2.0 * M_PI * (1.0 - std::cos(double(k.radius) * kDeg)) * k.above;
        if (k.above == 0.0)
            EXPECT_EQ(power, 0.0);
        else
            EXPECT_NEAR(power / want, 1.0, k.above < 1.0 ? 0.02 : 1e-3);
    }
}

TEST(Sky, FiniteAndNonNegative) {
    std::vector<et::SkyParams> cases(6);
    cases[1].sun_elevation_deg = 90.0f; // at the pole
    cases[2].sun_elevation_deg = 0.0f;  // on the horizon
    cases[2].sun_azimuth_deg = -180.0f; // on the seam
    cases[3].sun_angular_radius_deg = 0.0f;
    cases[4].sun_radiance = 1e6f;
    cases[4].ground_albedo = 1.0f;
    cases[5].sun_elevation_deg = -30.0f; // below the horizon
    for (size_t i = 0; i < cases.size(); ++i) {
        SCOPED_TRACE("case " + std::to_string(i));
        cases[i].width = 128;
        cases[i].height = 64;
        const et::RgbImage img = make_sky(cases[i]);
        ASSERT_EQ(img.rgb.size(), size_t(128 * 64 * 3));
        bool any_positive = false;
        for (float v : img.rgb) {
            ASSERT_TRUE(std::isfinite(v)) << v;
            ASSERT_GE(v, 0.0f);
            any_positive = any_positive || v > 0.0f;
        }
        EXPECT_TRUE(any_positive);
    }
}

TEST(Sky, ResolutionHonoured) {
    for (const auto& [w, h] :
         {std::make_pair(100, 37), std::make_pair(64, 32), std::make_pair(3, 2),
          std::make_pair(1, 1), std::make_pair(300, 10)}) {
        et::SkyParams p;
        p.width = w;
        p.height = h;
        const et::RgbImage img = make_sky(p);
        EXPECT_EQ(img.width, w);
        EXPECT_EQ(img.height, h);
        EXPECT_EQ(img.rgb.size(), static_cast<size_t>(w) * h * 3);
    }
}

TEST(Sky, SkyAndGroundFollowTheirParameters) {
    et::SkyParams p;
    p.width = 128;
    p.height = 64;
    et::SkyParams brighter = p, whiter = p, no_sun = p;
    brighter.sky_radiance = 2.0f;
    whiter.ground_albedo = 2.0f * p.ground_albedo;
    no_sun.sun_radiance = 0.0f;
    const et::RgbImage a = make_sky(p), sky2 = make_sky(brighter), ground2 = make_sky(whiter),
                       dark_sun = make_sky(no_sun);
    const etk::float3 sun = sun_direction(p.sun_elevation_deg, p.sun_azimuth_deg);
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x) {
            const bool upper = y < p.height / 2,
                       on_sun = angle_deg(texel_direction(a, x, y), sun) < 3.0;
            for (int c = 0; c < 3; ++c) {
                if (upper && !on_sun) { // sky: proportional to sky_radiance, blind to albedo
                    ASSERT_NEAR(sky2.at(x, y)[c], 2.0f * a.at(x, y)[c], 1e-5f * a.at(x, y)[c]);
                }
                if (upper) {
                    ASSERT_EQ(ground2.at(x, y)[c], a.at(x, y)[c]);
                }
                if (!upper) { // ground: uniform and proportional to the albedo
                    ASSERT_EQ(a.at(x, y)[c], a.at(0, p.height - 1)[c]) << x << "," << y;
                    ASSERT_NEAR(ground2.at(x, y)[c], 2.0f * a.at(x, y)[c], 1e-5f * a.at(x, y)[c]);
                }
            }
        }
    // The zenith is bluer than the horizon.
    const float* zenith = a.at(0, 0);
    EXPECT_GT(zenith[2], zenith[0]);
    const float* horizon = a.at(p.width / 2 + p.width / 4, p.height / 2 - 1);
    EXPECT_GT(horizon[0] / horizon[2], zenith[0] / zenith[2]);
    // The sun's share of the ground is the Lambertian reflection of its irradiance,
    // albedo / pi * L_sun * omega_sun * sin(elevation), times the ground colour.
    const double omega = 2.0 * M_PI * (1.0 - std::cos(p.sun_angular_radius_deg * kDeg));
    const double sun_part =
        p.ground_albedo / M_PI * p.sun_radiance * omega * std::sin(p.sun_elevation_deg * kDeg);
    const float* g = a.at(0, p.height - 1);
    const float* g0 = dark_sun.at(0, p.height - 1);
    const double ground_colour[3] = {0.42, 0.36, 0.30};
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(g[c] - g0[c], sun_part * ground_colour[c], 1e-3 * sun_part) << c;
}

} // namespace
