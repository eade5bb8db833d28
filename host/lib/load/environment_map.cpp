#include "load/environment_map.h"

#include "util/checked_size.h"
#include "util/error.h"
#include "util/json_file.h"
#include "util/parallel.h"
#include "util/timer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace et {

etk::EtkEnvMap EnvMap::desc() const {
    etk::EtkEnvMap d;
    d.tex_w = image.width;
    d.tex_h = image.height;
    d.dist_w = dist.width;
    d.dist_h = dist.height;
    d.scale = scale;
    const double a = rotation_degrees * M_PI / 180.0;
    d.rot_cos = static_cast<float>(std::cos(a));
    d.rot_sin = static_cast<float>(std::sin(a));
    d.has_light = dist.has_light() && scale > 0.0f ? 1 : 0;
    return d;
}

SanitizeReport sanitize_texels(RgbImage& image) {
    // In slices on every core: a 16k map has 400M channels.
    const size_t n = image.rgb.size() / 3;
    const int threads = static_cast<int>(
        std::clamp<size_t>(n / (1 << 20), 1, static_cast<size_t>(thread_count(0))));
    std::vector<SanitizeReport> parts(threads);
    run_on_threads(threads, [&](int part) {
        SanitizeReport& r = parts[part];
        const size_t first = n * part / threads, last = n * (part + 1) / threads;
        constexpr size_t kBlock = 4096; // texels checked at once, branch-free (vectorised)
        for (size_t b = first; b < last; b += kBlock) {
            const size_t e = std::min(last, b + kBlock);
            const float* v = &image.rgb[3 * b];
            bool ok = true;
            float mx = r.max_value;
            for (size_t i = 0, m = 3 * (e - b); i < m; ++i) {
                ok &= v[i] >= 0.0f && v[i] <= kMaxRadiance; // false for NaN
                mx = v[i] > mx ? v[i] : mx;
            }
            if (ok) {
                r.max_value = mx;
                continue;
            }
            for (size_t p = b; p < e; ++p) {
                float* t = &image.rgb[3 * p];
                bool bad = false, neg = false, bright = false;
                for (int c = 0; c < 3; ++c) {
                    if (!std::isfinite(t[c])) {
                        t[c] = 0.0f;
                        bad = true;
                    } else if (t[c] < 0.0f) {
                        t[c] = 0.0f;
                        neg = true;
                    } else if (t[c] > kMaxRadiance) {
                        t[c] = kMaxRadiance;
                        bright = true;
                    }
                    r.max_value = std::max(r.max_value, t[c]);
                }
                r.non_finite += bad;
                r.negative += neg && !bad;
                r.too_bright += bright && !neg && !bad;
            }
        }
    });
    SanitizeReport r;
    for (const SanitizeReport& p : parts) {
        r.non_finite += p.non_finite;
        r.negative += p.negative;
        r.too_bright += p.too_bright;
        r.max_value = std::max(r.max_value, p.max_value);
    }
    return r;
}

EnvMap make_envmap(std::string name, RgbImage image, const DistributionOptions& options) {
    EnvMap env;
    env.name = std::move(name);
    env.image = std::move(image);
    SanitizeReport r = sanitize_texels(env.image);
    if (r.non_finite + r.negative > 0)
        warn(env.name + ": " + std::to_string(r.non_finite) + " non-finite and " +
             std::to_string(r.negative) +
             " negative texels set to zero (they are ignored for lighting and sampling)");
    if (r.too_bright > 0)
        warn(env.name + ": " + std::to_string(r.too_bright) +
             " texels brighter than 1e12 clamped to it (no output may overflow)");
    env.max_texel = r.max_value;
    if (env.image.width != 2 * env.image.height)
        warn(env.name + ": " + std::to_string(env.image.width) + "x" +
             std::to_string(env.image.height) +
             " is not a 2:1 lat-long map; it is stretched over the sphere as it is");
    if (3 * static_cast<uint64_t>(env.image.width) * static_cast<uint64_t>(env.image.height) >
        kMaxDeviceIndex)
        throw Error(env.name + ": " + std::to_string(env.image.width) + "x" +
                    std::to_string(env.image.height) + " texels: more than the device indexes");
    if (options.width < 0 || options.height < 0)
        throw Error(env.name + ": distribution resolution " + std::to_string(options.width) + "x" +
                    std::to_string(options.height) + " is out of range");
    if (!(options.blur_sigma >= 0.0f && options.blur_sigma <= kMaxBlurSigma))
        throw Error(env.name + ": blur " + std::to_string(options.blur_sigma) + " is outside [0, " +
                    std::to_string(int(kMaxBlurSigma)) + "] texels");
    try {
        check_distribution_size(options.width > 0 ? options.width : env.image.width,
                                options.height > 0 ? options.height : env.image.height);
    } catch (const Error& e) {
        throw Error(env.name + ": " + e.what());
    }
    Timer t;
    env.dist = build_env_distribution(env.image, options);
    env.build_seconds = t.seconds();
    if (!env.dist.has_light())
        warn(env.name + ": the map is black everywhere; it emits no light");
    return env;
}

EnvMap load_envmap(const std::string& path, const DistributionOptions& options) {
    Timer t;
    RgbImage img = read_rgb_image(path);
    double load = t.seconds();
    EnvMap env = make_envmap(path, std::move(img), options);
    env.load_seconds = load;
    return env;
}

void bound_intensity(EnvMap& env, const std::string& where) {
    if (env.max_texel > 0.0f && static_cast<double>(env.scale) * env.max_texel > kMaxRadiance) {
        const float bounded = kMaxRadiance / env.max_texel;
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      ": %g times the brightest texel (%g) exceeds %g; intensity clamped to %g",
                      double(env.scale), double(env.max_texel), double(kMaxRadiance),
                      double(bounded));
        warn(where + buf);
        env.scale = bounded;
    }
}

void parse_resolution(const std::string& text, int& width, int& height) {
    long long w = 0, h = 0;
    char x = 0, extra = 0;
    if (text.size() > 32 || std::sscanf(text.c_str(), "%lld%c%lld%c", &w, &x, &h, &extra) != 3 ||
        (x != 'x' && x != 'X') || w < 1 || h < 1 || w > kMaxDistributionSide ||
        h > kMaxDistributionSide)
        throw Error("resolution '" + excerpt(text, 40) +
                    "' is not WIDTHxHEIGHT (e.g. 512x256, 1 to 65536)");
    width = static_cast<int>(w);
    height = static_cast<int>(h);
    check_distribution_size(width, height);
}

} // namespace et
