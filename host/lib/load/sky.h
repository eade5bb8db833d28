// A procedural sun-and-sky lat-long map, so the default scene needs no downloaded data.
#pragma once
#include "image/image_io.h"

namespace et {

struct SkyParams {
    int width = 1024, height = 512;
    float sun_elevation_deg = 35.0f, sun_azimuth_deg = 40.0f; // azimuth from -Z towards +X
    float sun_angular_radius_deg = 0.8f;
    float sun_radiance = 3000.0f; // per channel, before the sun colour
    float sky_radiance = 1.0f;    // zenith luminance scale
    float ground_albedo = 0.3f;
};

// Sky: a zenith-to-horizon gradient with a glow around the sun; ground: a uniform grey-brown lit
// by sun and sky; sun: a disc, hidden where it is below the horizon. Each texel is the mean of
// 4x4 sub-samples so the disc is smooth; a disc under two texels across is put in by 4096 points
// over its solid angle instead, so that its power is exact however small it is.
RgbImage make_sky(const SkyParams& p);

} // namespace et
