// Checks the optimised build_env_distribution against the original implementation on real,
// synthetic and degenerate maps, several blur sigmas, distribution resolutions and thread counts:
// densities within float rounding, CDFs monotone with cdf[0] == 0 and cdf[n] == 1, same total.
// A check tool for the optimisation, run by hand (see README.md); not a ctest test.
#include "baseline_env_distribution.h"
#include "bench_maps.h"
#include "env_distribution.h"
#include "kernels/piecewise_constant.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace {

struct Stats {
    double max_rel_pdf = 0.0, max_abs_cdf = 0.0;
    long bitwise_diff = 0;
};

bool check_cdf(const float* cdf, int n, const std::string& what) {
    if (cdf[0] != 0.0f || cdf[n] != 1.0f) {
        std::printf("FAIL %s: cdf[0]=%g cdf[n]=%g\n", what.c_str(), cdf[0], cdf[n]);
        return false;
    }
    for (int i = 0; i < n; ++i)
        if (!(cdf[i + 1] >= cdf[i])) {
            std::printf("FAIL %s: cdf not monotone at %d\n", what.c_str(), i);
            return false;
        }
    return true;
}

bool compare(const std::string& name, const et::RgbImage& img, et::DistributionOptions opt) {
    const et::EnvDistribution a = et::baseline::build_env_distribution(img, opt);
    const et::EnvDistribution b = et::build_env_distribution(img, opt);
    char label[256];
    std::snprintf(label, sizeof label, "%s sigma=%.2f res=%dx%d threads=%d", name.c_str(),
                  opt.blur_sigma, b.width, b.height, opt.threads);
    if (a.table.size() != b.table.size() || a.width != b.width || a.height != b.height) {
        std::printf("FAIL %s: table shapes differ\n", label);
        return false;
    }
    const int w = b.width, h = b.height;
    bool ok = check_cdf(b.table.data() + etk::etk_dist2d_marginal_cdf(h), h, label);
    for (int y = 0; y < h && ok; ++y)
        ok = check_cdf(b.table.data() + etk::etk_dist2d_conditional_cdf(w, h) +
                           static_cast<size_t>(y) * (w + 1),
                       w, label);
    Stats s;
    const size_t cdf_start = etk::etk_dist2d_conditional_cdf(w, h);
    for (size_t i = 0; i < a.table.size(); ++i) {
        const float x = a.table[i], z = b.table[i];
        if (x != z)
            ++s.bitwise_diff;
        const bool is_cdf =
            (i >= static_cast<size_t>(h) && i < 2 * static_cast<size_t>(h) + 1) || i >= cdf_start;
        if (is_cdf)
            s.max_abs_cdf = std::max(s.max_abs_cdf, std::fabs(double(x) - z));
        else if (x != z)
            s.max_rel_pdf =
                std::max(s.max_rel_pdf, std::fabs(double(x) - z) / std::max(std::fabs(x), 1e-30f));
    }
    const double rel_total = a.total > 0 ? std::fabs(a.total - b.total) / a.total : b.total;
    // Float rounding: a couple of ulps (the double sums are reassociated, the floats are not).
    ok = ok && s.max_rel_pdf <= 3e-7 && s.max_abs_cdf <= 1.2e-7 && rel_total <= 1e-12;
    std::printf("%s %-60s differing floats %ld of %zu, max rel pdf %.2e, max abs cdf %.2e, "
                "total rel %.1e\n",
                ok ? "ok  " : "FAIL", label, s.bitwise_diff, a.table.size(), s.max_rel_pdf,
                s.max_abs_cdf, rel_total);
    return ok;
}

et::RgbImage constant(int w, int h, float v) {
    et::RgbImage img;
    img.width = w;
    img.height = h;
    img.rgb.assign(3 * static_cast<size_t>(w) * h, v);
    return img;
}

} // namespace

int main() {
    bool ok = true;
    const char* real[] = {"royal_esplanade_1k.hdr", "grace.hdr", "pedestrian_overpass_1k.hdr",
                          "spot1Lux.hdr", "museum_wells6.exr"};
    for (const char* name : real)
        for (float sigma : {0.5f, 0.0f, 2.0f})
            for (int threads : {1, 2}) {
                et::DistributionOptions o;
                o.blur_sigma = sigma;
                o.threads = threads;
                ok &= compare(name, et::bench::real_map(name), o);
            }
    const int res[][2] = {{512, 256}, {300, 177}, {2048, 1024}, {1, 1}, {7, 3}};
    for (const char* name : {"royal_esplanade_1k.hdr", "grace.hdr"})
        for (const auto& r : res)
            for (int threads : {1, 2}) {
                et::DistributionOptions o;
                o.width = r[0];
                o.height = r[1];
                o.threads = threads;
                ok &= compare(name, et::bench::real_map(name), o);
            }
    ok &= compare("sky", et::bench::sky_map(1024, 512), {});
    et::RgbImage one = constant(64, 32, 0.0f);
    one.at(17, 9)[1] = 5.0f;
    for (float sigma : {0.0f, 0.5f}) {
        et::DistributionOptions o;
        o.blur_sigma = sigma;
        ok &= compare("one-lit-texel", one, o);
        ok &= compare("black", constant(64, 32, 0.0f), o);
        ok &= compare("constant", constant(64, 32, 1.0f), o);
        ok &= compare("2x1", constant(2, 1, 1.0f), o);
        ok &= compare("1x1", constant(1, 1, 1.0f), o);
        ok &= compare("3x1000", constant(3, 1000, 2.0f), o);
    }
    std::printf(ok ? "all match\n" : "MISMATCH\n");
    return ok ? 0 : 1;
}
