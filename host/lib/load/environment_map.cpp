#include "load/environment_map.h"

#include "util/checked_size.h"
#include "util/error.h"
#include "util/json_file.h"
#include "util/parallel.h"
#include "util/prefault.h"
#include "util/timer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>

namespace et {

double texel_solid_angle(int row, int w, int h) {
    const double t0 = M_PI * row / h, t1 = M_PI * (row + 1) / h;
    return 2.0 * M_PI / w * (std::cos(t0) - std::cos(t1));
}

double convention_rotation_degrees(LatLongConvention c) {
    switch (c) {
    case LatLongConvention::mitsuba:
        return 180.0;
    case LatLongConvention::blender:
        return 90.0;
    case LatLongConvention::envtrace:
        break;
    }
    return 0.0;
}

const char* name_of(LatLongConvention c) {
    switch (c) {
    case LatLongConvention::mitsuba:
        return "mitsuba";
    case LatLongConvention::blender:
        return "blender";
    case LatLongConvention::envtrace:
        break;
    }
    return "envtrace";
}

bool parse_convention(const std::string& name, LatLongConvention& out) {
    for (LatLongConvention c :
         {LatLongConvention::envtrace, LatLongConvention::mitsuba, LatLongConvention::blender})
        if (name == name_of(c)) {
            out = c;
            return true;
        }
    return false;
}

etk::EtkEnvMap EnvMap::desc() const {
    etk::EtkEnvMap d;
    d.tex_w = image.width;
    d.tex_h = image.height;
    d.dist_w = dist.width;
    d.dist_h = dist.height;
    d.scale = scale;
    // Reduced to [-180, 180] first, so that the conventions' quarter and half turns stay exact.
    const double a =
        std::remainder(double(rotation_degrees) + convention_rotation_degrees(convention), 360.0) *
        M_PI / 180.0;
    d.rot_cos = static_cast<float>(std::cos(a));
    d.rot_sin = static_cast<float>(std::sin(a));
    d.has_light = dist.has_light() && scale > 0.0f ? 1 : 0;
    d.black_w = d.black_h = 0; // no black mask unless the preparation builds one
    d.lit_sr = static_cast<float>(4.0 * M_PI);
    return d;
}

namespace {

// Sanitises n texels from rgb on, adding to r.
void sanitize_range(float* rgb, size_t n, SanitizeReport& r) {
    // The bits of a float in [+0, kMaxRadiance], read as an unsigned int, are at most those of
    // kMaxRadiance and ordered as the floats are; negative values (-0 too), NaN and Inf are above.
    // So one unsigned max over a block, which vectorises (float compares did not), tells whether
    // the block is clean and gives its largest value.
    uint32_t max_bits;
    std::memcpy(&max_bits, &kMaxRadiance, sizeof max_bits);
    constexpr size_t kBlock = 4096; // texels checked at once
    for (size_t b = 0; b < n; b += kBlock) {
        const size_t e = std::min(n, b + kBlock);
        const float* v = rgb + 3 * b;
        uint32_t top = 0;
        for (size_t i = 0, m = 3 * (e - b); i < m; ++i) {
            uint32_t u;
            std::memcpy(&u, v + i, sizeof u);
            top = u > top ? u : top;
        }
        if (top <= max_bits) {
            float mx;
            std::memcpy(&mx, &top, sizeof mx);
            r.max_value = std::max(r.max_value, mx);
            continue;
        }
        for (size_t p = b; p < e; ++p) {
            float* t = rgb + 3 * p;
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
}

void warn_sanitized(const std::string& name, const SanitizeReport& r) {
    if (r.non_finite + r.negative > 0)
        warn(name + ": " + std::to_string(r.non_finite) + " non-finite and " +
             std::to_string(r.negative) +
             " negative texels set to zero (they are ignored for lighting and sampling)");
    if (r.too_bright > 0)
        warn(name + ": " + std::to_string(r.too_bright) +
             " texels brighter than 1e12 clamped to it (no output may overflow)");
}

// What make_envmap and load_envmap check before building (load_envmap before decoding).
void check_map(const std::string& name, int width, int height, const DistributionOptions& options) {
    if (width != 2 * height)
        warn(name + ": " + std::to_string(width) + "x" + std::to_string(height) +
             " is not a 2:1 lat-long map; it is stretched over the sphere as it is");
    if (3 * static_cast<uint64_t>(width) * static_cast<uint64_t>(height) > kMaxDeviceIndex)
        throw Error(name + ": " + std::to_string(width) + "x" + std::to_string(height) +
                    " texels: more than the device indexes");
    if (options.width < 0 || options.height < 0)
        throw Error(name + ": distribution resolution " + std::to_string(options.width) + "x" +
                    std::to_string(options.height) + " is out of range");
    if (!(options.blur_sigma >= 0.0f && options.blur_sigma <= kMaxBlurSigma))
        throw Error(name + ": blur " + std::to_string(options.blur_sigma) + " is outside [0, " +
                    std::to_string(int(kMaxBlurSigma)) + "] texels");
    try {
        check_distribution_size(options.width > 0 ? options.width : width,
                                options.height > 0 ? options.height : height);
    } catch (const Error& e) {
        throw Error(name + ": " + e.what());
    }
}

} // namespace

SanitizeReport sanitize_texels(RgbImage& image) {
    // In slices on every core: a 16k map has 400M channels.
    const size_t n = image.rgb.size() / 3;
    const int threads = static_cast<int>(
        std::clamp<size_t>(n / (1 << 20), 1, static_cast<size_t>(thread_count(0))));
    std::vector<SanitizeReport> parts(threads);
    run_on_threads(threads, [&](int part) {
        const size_t first = n * part / threads, last = n * (part + 1) / threads;
        sanitize_range(image.rgb.data() + 3 * first, last - first, parts[part]);
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
    warn_sanitized(env.name, r);
    env.max_texel = r.max_value;
    check_map(env.name, env.image.width, env.image.height, options);
    Timer t;
    env.dist = build_env_distribution(env.image, options);
    env.build_seconds = t.seconds();
    if (!env.dist.has_light())
        warn(env.name + ": the map is black everywhere; it emits no light");
    return env;
}

EnvMap load_envmap(const std::string& path, const DistributionOptions& options) {
    Timer total;
    RgbImageReader reader(path);
    const int w = reader.width(), h = reader.height();
    check_map(path, w, h, options); // before a texel is decoded
    EnvMap env;
    env.name = path;
    env.image.width = w;
    env.image.height = h;

    // Thread 0 decodes and sanitises the map a band of rows at a time; the others build the
    // distribution's blocks as soon as the rows they read are final, and thread 0 joins them when
    // the map is decoded. Only the builders ever wait, and only for rows, so a part run late on
    // the calling thread (run_on_threads' fallback) never waits for one that has not run yet.
    std::mutex mutex;
    std::condition_variable rows_cv;
    int rows_ready = 0;              // under mutex
    std::atomic<bool> failed{false}; // a part threw: the others stop
    std::mutex builder_mutex;
    std::unique_ptr<DistributionBuilder> builder; // made by the first part to need it
    std::atomic<int> next_block{0};
    std::atomic<int64_t> build_ns{0}; // thread time spent on the distribution
    SanitizeReport report;
    env.image.rgb.reserve(static_cast<size_t>(w) * h * 3);
    float* const texels = env.image.rgb.data(); // fixed: the vector only grows within capacity

    auto timed = [&](auto&& work) {
        Timer t;
        work();
        build_ns += static_cast<int64_t>(t.seconds() * 1e9);
    };
    auto build_blocks = [&] {
        {
            // The distribution's table (as many cells as texels by default) is allocated once the
            // first band has decoded, not before: a file that declares a huge size and holds
            // little fails first (F7).
            std::unique_lock<std::mutex> lock(mutex);
            rows_cv.wait(lock, [&] { return failed || rows_ready > 0; });
        }
        DistributionBuilder* b = nullptr;
        {
            std::lock_guard<std::mutex> lock(builder_mutex);
            if (!builder && !failed)
                timed([&] { builder = std::make_unique<DistributionBuilder>(w, h, options); });
            b = builder.get();
        }
        if (!b)
            return;
        for (int k = next_block++; k < b->blocks(); k = next_block++) {
            {
                std::unique_lock<std::mutex> lock(mutex);
                const int need = b->rows_needed(k);
                rows_cv.wait(lock, [&] { return failed || rows_ready >= need; });
            }
            if (failed)
                return;
            timed([&] { b->build_block(texels, k); });
        }
    };
    // A map of one band and one block gains nothing from a second thread.
    const int threads = h > 256 ? thread_count(options.threads) : 1;
    run_on_threads(threads, [&](int part) {
        try {
            if (part == 0) {
                // The texels are reserved whole (address space only) and grown a band at a time
                // as the file decodes, never moving (the builders read them meanwhile through
                // `texels`): a file that declares more pixels than it holds fails before that
                // memory is touched (fuzz finding F7).
                const size_t row = static_cast<size_t>(w) * 3;
                const int band = reader.band_rows();
                for (int y = 0; y < h && !failed;) {
                    grow_in_place(env.image.rgb, row * std::min(h, y + band));
                    float* rows = texels + row * y;
                    const int n = reader.read_rows(band, rows);
                    sanitize_range(rows, static_cast<size_t>(n) * w, report);
                    y += n;
                    {
                        std::lock_guard<std::mutex> lock(mutex);
                        rows_ready = y;
                    }
                    rows_cv.notify_all();
                }
                env.load_seconds = total.seconds();
            }
            build_blocks();
        } catch (...) {
            {
                std::lock_guard<std::mutex> lock(mutex);
                failed = true;
            }
            rows_cv.notify_all();
            throw;
        }
    });
    const int builders = std::min(threads, builder->blocks());
    timed([&] { env.dist = builder->finish(); });
    env.build_seconds = build_ns * 1e-9 / builders;

    warn_sanitized(path, report);
    env.max_texel = report.max_value;
    if (!env.dist.has_light())
        warn(env.name + ": the map is black everywhere; it emits no light");
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
    // The film sums samples in fixed point, units of 2^-70 (render/film_sums.h): exact to float
    // precision above 2^-46, coarser below, and 0 under 2^-71. A map that dim would render as
    // black or a few percent off without a word.
    const double brightest = static_cast<double>(env.scale) * env.max_texel;
    if (brightest > 0.0 && brightest < std::ldexp(1.0, -46)) {
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      ": the brightest texel times the intensity is %g, below what the film holds "
                      "to float precision (%g); the image would be black or off: raise the "
                      "intensity and scale the image down afterwards",
                      brightest, std::ldexp(1.0, -46));
        warn(where + buf);
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
