#include "image/preview.h"

#include "load/env_distribution.h"
#include "load/environment_map.h"

#include <algorithm>
#include <cmath>

namespace et {

std::vector<float> tone_map(const RgbImage& img, float exposure) {
    const size_t n = static_cast<size_t>(img.width) * img.height;
    if (!(exposure > 0.0f)) {
        double log_sum = 0.0; // geometric mean: robust to a tiny, very bright sun
        for (size_t p = 0; p < n; ++p)
            log_sum += std::log(1e-4 + std::max(0.0f, luminance(&img.rgb[3 * p])));
        exposure = static_cast<float>(0.18 / std::exp(log_sum / std::max<size_t>(1, n)));
    }
    std::vector<float> out(3 * n);
    for (size_t p = 0; p < n; ++p) {
        const float* c = &img.rgb[3 * p];
        float y = std::max(0.0f, luminance(c)) * exposure;
        float k = y > 0.0f ? exposure / (1.0f + y) : 0.0f;
        for (int i = 0; i < 3; ++i)
            out[3 * p + i] = linear_to_srgb(c[i] * k);
    }
    return out;
}

void draw_dot(std::vector<float>& display, int width, int height, float u, float v, int radius,
              const float colour[3]) {
    const int cx = static_cast<int>(u * width), cy = static_cast<int>(v * height);
    const int outer = radius + 1;
    for (int dy = -outer; dy <= outer; ++dy)
        for (int dx = -outer; dx <= outer; ++dx) {
            const int d2 = dx * dx + dy * dy;
            if (d2 > outer * outer)
                continue;
            const int y = cy + dy;
            if (y < 0 || y >= height)
                continue;
            const int x = ((cx + dx) % width + width) % width;
            float* px = &display[3 * (static_cast<size_t>(y) * width + x)];
            const bool inside = d2 <= radius * radius;
            for (int c = 0; c < 3; ++c)
                px[c] = inside ? colour[c] : 0.0f;
        }
}

void write_direction_plot(OutputBatch& batch, const std::string& path, const EnvMap& env,
                          const std::vector<std::array<float, 3>>& directions) {
    std::vector<float> display = tone_map(env.image);
    const int radius = std::max(1, env.image.width / 256);
    const float colour[3] = {1.0f, 0.15f, 0.1f};
    const etk::EtkEnvMap desc = env.desc();
    for (const auto& d : directions) {
        const etk::float2 uv = etk::etk_dir_to_latlong(
            etk::etk_world_to_env(desc, etk::make_float3(d[0], d[1], d[2])));
        draw_dot(display, env.image.width, env.image.height, uv.x, uv.y, radius, colour);
    }
    write_image(batch, path, env.image.width, env.image.height, 3, display,
                {{"Software", "envtrace " ENVTRACE_VERSION}});
}

} // namespace et
