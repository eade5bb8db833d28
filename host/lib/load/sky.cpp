#include "load/sky.h"

#include "kernels/latlong.h"

#include <algorithm>
#include <cmath>

namespace et {

RgbImage make_sky(const SkyParams& p) {
    const float el = p.sun_elevation_deg * float(M_PI) / 180.0f;
    const float az = p.sun_azimuth_deg * float(M_PI) / 180.0f;
    const etk::float3 sun =
        etk::make_float3(std::cos(el) * std::sin(az), std::sin(el), -std::cos(el) * std::cos(az));
    const float cos_sun = std::cos(p.sun_angular_radius_deg * float(M_PI) / 180.0f);
    const float zenith[3] = {0.22f, 0.42f, 0.95f}, horizon[3] = {0.85f, 0.88f, 0.95f};
    const float ground[3] = {0.42f, 0.36f, 0.30f};
    const float sun_col[3] = {1.0f, 0.93f, 0.82f};
    // Ground radiance: diffuse reflection of sun (cosine at its elevation) and half the sky.
    const float ground_light =
        p.ground_albedo *
        (std::max(0.0f, std::sin(el)) * p.sun_radiance * 2.0f * float(M_PI) * (1.0f - cos_sun) +
         0.5f * p.sky_radiance * float(M_PI)) /
        float(M_PI);

    RgbImage img;
    img.width = p.width;
    img.height = p.height;
    img.rgb.assign(static_cast<size_t>(p.width) * p.height * 3, 0.0f);
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
                        } else {
                            v = ground_light * ground[k];
                        }
                        if (c >= cos_sun)
                            v = p.sun_radiance * sun_col[k];
                        acc[k] += v;
                    }
                }
            for (int k = 0; k < 3; ++k)
                img.at(x, y)[k] = acc[k] / (ss * ss);
        }
    return img;
}

} // namespace et
