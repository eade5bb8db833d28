#include "load/sky.h"

#include "kernels/bsdf.h"
#include "kernels/latlong.h"
#include "load/environment_map.h"

#include <algorithm>
#include <cmath>

namespace et {

RgbImage make_sky(const SkyParams& p) {
    const float el = p.sun_elevation_deg * float(M_PI) / 180.0f;
    const float az = p.sun_azimuth_deg * float(M_PI) / 180.0f;
    const etk::float3 sun =
        etk::make_float3(std::cos(el) * std::sin(az), std::sin(el), -std::cos(el) * std::cos(az));
    const double r = double(p.sun_angular_radius_deg) * M_PI / 180.0;
    const float cos_sun = std::cos(p.sun_angular_radius_deg * float(M_PI) / 180.0f);
    const double one_minus_cos = 2.0 * std::sin(0.5 * r) * std::sin(0.5 * r); // exact when tiny
    const double sun_omega = 2.0 * M_PI * one_minus_cos; // the disc's solid angle
    const float zenith[3] = {0.22f, 0.42f, 0.95f}, horizon[3] = {0.85f, 0.88f, 0.95f};
    const float ground[3] = {0.42f, 0.36f, 0.30f};
    const float sun_col[3] = {1.0f, 0.93f, 0.82f};
    // Ground radiance: diffuse reflection of sun (cosine at its elevation) and half the sky.
    const float ground_light =
        p.ground_albedo *
        (std::max(0.0f, std::sin(el)) * p.sun_radiance * static_cast<float>(sun_omega) +
         0.5f * p.sky_radiance * float(M_PI)) /
        float(M_PI);

    RgbImage img;
    img.width = p.width;
    img.height = p.height;
    img.rgb.assign(static_cast<size_t>(p.width) * p.height * 3, 0.0f);
    const double dv = M_PI / p.height; // a texel row's angle
    // A disc of at least two texels is drawn by the texels' 4 x 4 sub-samples; a smaller one by
    // its own points below: a disc narrower than the sub-samples would fall between them and be
    // lost, and one of a few texels would get the wrong power.
    const bool small_disc = r < 2.0 * dv;
    const int ss = 4;
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x) {
            float acc[3] = {0, 0, 0};
            for (int sy = 0; sy < ss; ++sy)
                for (int sx = 0; sx < ss; ++sx) {
                    etk::float2 uv = etk::make_float2((x + (sx + 0.5f) / ss) / p.width,
                                                      (y + (sy + 0.5f) / ss) / p.height);
                    etk::float3 d = etk::etk_latlong_to_dir(uv);
                    float c = etk::dot(d, sun);
                    for (int k = 0; k < 3; ++k) {
                        float v;
                        if (d.y >= 0.0f) {
                            float t = std::pow(1.0f - d.y, 4.0f);
                            float glow = 0.6f * std::exp((c - 1.0f) * 8.0f) +
                                         2.0f * std::exp((c - 1.0f) * 200.0f);
                            v = p.sky_radiance *
                                ((1 - t) * zenith[k] + t * horizon[k] + glow * sun_col[k]);
                            if (!small_disc && c >= cos_sun) // the ground hides a setting sun
                                v = p.sun_radiance * sun_col[k];
                        } else {
                            v = ground_light * ground[k];
                        }
                        acc[k] += v;
                    }
                }
            for (int k = 0; k < 3; ++k)
                img.at(x, y)[k] = acc[k] / (ss * ss);
        }

    // A small disc: 64 x 64 points stratified over its solid angle (cos uniform in [cos r, 1],
    // longitude uniform), each carrying 1/4096 of its power (radiance x solid angle) into the
    // texel it falls in, unless below the horizon. Its power is exact at any radius and
    // resolution, whatever the grid makes of its shape.
    if (small_disc && sun_omega > 0.0 && p.sun_radiance > 0.0f) {
        etk::float3 t, b;
        etk::etk_make_frame(sun, &t, &b);
        constexpr int n = 64;
        const double share = sun_omega / (n * n);
        for (int i = 0; i < n; ++i) {
            const double a = (i + 0.5) / n * one_minus_cos; // 1 - cos(theta)
            const double sin_t = std::sqrt(a * (2.0 - a)), cos_t = 1.0 - a;
            for (int j = 0; j < n; ++j) {
                const double phi = 2.0 * M_PI * (j + 0.5) / n;
                const double cx = sin_t * std::cos(phi), cy = sin_t * std::sin(phi);
                const etk::float3 d = etk::make_float3(float(cos_t * sun.x + cx * t.x + cy * b.x),
                                                       float(cos_t * sun.y + cx * t.y + cy * b.y),
                                                       float(cos_t * sun.z + cx * t.z + cy * b.z));
                if (d.y < 0.0f)
                    continue;
                const etk::float2 uv = etk::etk_dir_to_latlong(etk::normalize(d));
                const int x = std::clamp(static_cast<int>(uv.x * p.width), 0, p.width - 1);
                const int y = std::clamp(static_cast<int>(uv.y * p.height), 0, p.height - 1);
                const double texel = texel_solid_angle(y, p.width, p.height);
                for (int k = 0; k < 3; ++k)
                    img.at(x, y)[k] +=
                        static_cast<float>(share / texel) * p.sun_radiance * sun_col[k];
            }
        }
    }
    return img;
}

} // namespace et
