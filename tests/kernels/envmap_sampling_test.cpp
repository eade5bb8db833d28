// The OpenCL sampling kernel (EnvSamplerCL on PoCL) against the host reference built from the
// same shared headers (sample_env_host), on identical uniforms: same cells, same directions,
// densities and radiance up to the device's float rounding. And the device's batches of light
// samples (the sample_lights stage's etk_env_light_batch) against its own samples one by one: the
// same bits, field by field, so that --light-batch never changes an image on any device.
#include "render/env_sampling.h"
#include "kernels/piecewise_constant.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>

namespace {

// Random uniforms plus the edges: 0, the largest float below 1, and values exactly on CDF
// entries (the marginal's, and for a few rows, their conditional's with that row selected).
std::vector<float> test_uniforms(const et::EnvMap& env, int random_count) {
    std::vector<float> u;
    auto push = [&](float x, float y) {
        u.push_back(std::min(x, ETK_ONE_MINUS_EPS));
        u.push_back(std::min(y, ETK_ONE_MINUS_EPS));
    };
    const float edges[] = {0.0f, 1e-7f, 0.5f, 0.9999999f, ETK_ONE_MINUS_EPS};
    for (float x : edges)
        for (float y : edges)
            push(x, y);
    const int w = env.dist.width, h = env.dist.height;
    const float* t = env.dist.table.data();
    const float* marginal_cdf = t + etk::etk_dist2d_marginal_cdf(h);
    for (int r = 0; r <= h; ++r)
        for (float x : edges)
            push(x, marginal_cdf[r]);
    std::mt19937 rng(99);
    for (int k = 0; k < 8; ++k) {
        const int r = static_cast<int>(rng() % h);
        const float* cond_cdf = t + etk::etk_dist2d_conditional_cdf(w, h) + r * (w + 1);
        for (int c = 0; c <= w; ++c) {
            push(cond_cdf[c], marginal_cdf[r]);
            push(std::nextafter(cond_cdf[c], 0.0f), marginal_cdf[r]);
        }
    }
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    for (int k = 0; k < random_count; ++k)
        push(uni(rng), uni(rng));
    return u;
}

void compare_kernel_and_host(const std::string& name, const et::EnvMap& env) {
    SCOPED_TRACE(name);
    const std::vector<float> uniforms = test_uniforms(env, 1 << 16);
    et::EnvSamplerCL cl(ett::runtime(), env);
    const auto dev = cl.sample_uniforms(uniforms);
    const auto host = et::sample_env_host(env, uniforms);
    ASSERT_EQ(dev.size(), host.size());
    int failures = 0;
    size_t radiance_off = 0;
    for (size_t i = 0; i < dev.size() && failures < 10; ++i) {
        const auto &a = dev[i], &b = host[i];
        bool ok = a.row == b.row && a.col == b.col;
        for (int c = 0; c < 3; ++c) // unit vectors: absolute is relative
            ok = ok && std::isfinite(a.dir[c]) && std::fabs(a.dir[c] - b.dir[c]) <= 1e-5f;
        ok = ok && std::isfinite(a.pdf) && std::fabs(a.pdf - b.pdf) <= 1e-5f * b.pdf;
        ok = ok && (!env.dist.has_light() || a.pdf > 0.0f);
        // Radiance: finite and non-negative, and equal within rounding: both sides look it up
        // at the sample's own (u, v), computed by the same operations.
        for (int c = 0; c < 3; ++c) {
            ok = ok && std::isfinite(a.radiance[c]) && a.radiance[c] >= 0.0f;
            if (std::fabs(a.radiance[c] - b.radiance[c]) > 1e-5f * b.radiance[c] + 1e-30f)
                ++radiance_off;
        }
        if (!ok) {
            ++failures;
            ADD_FAILURE() << "uniform (" << uniforms[2 * i] << ", " << uniforms[2 * i + 1]
                          << "): kernel cell (" << a.row << ", " << a.col << ") dir (" << a.dir[0]
                          << ", " << a.dir[1] << ", " << a.dir[2] << ") pdf " << a.pdf << " L "
                          << a.radiance[0] << "; host cell (" << b.row << ", " << b.col << ") dir ("
                          << b.dir[0] << ", " << b.dir[1] << ", " << b.dir[2] << ") pdf " << b.pdf
                          << " L " << b.radiance[0];
        }
    }
    EXPECT_EQ(radiance_off, 0u) << "radiance channels differing by more than 1e-5 relative";
    std::printf("%s: %zu of %zu radiance channels differ by more than 1e-5 relative\n",
                name.c_str(), radiance_off, 3 * dev.size());

    const auto batched = cl.sample_uniforms_batched(uniforms);
    ASSERT_EQ(batched.size(), dev.size());
    static_assert(sizeof(et::EnvSampleRecord) == 10 * 4, "eight floats and two ints");
    static const char* const kField[] = {"dir.x", "dir.y", "dir.z", "pdf", "L.r",
                                         "L.g",   "L.b",   "pad",   "row", "col"};
    int differ[10] = {}, shown = 0;
    for (size_t i = 0; i < dev.size(); ++i) {
        // The record's eight floats (dir, pdf, radiance, pad) and two ints, as raw bits.
        uint32_t a[10], b[10];
        std::memcpy(a, &batched[i], sizeof(a));
        std::memcpy(b, &dev[i], sizeof(b));
        for (int f = 0; f < 10; ++f) {
            if (a[f] != b[f] && ++differ[f] && shown < 5) {
                ++shown;
                float fa, fb;
                std::memcpy(&fa, &a[f], 4);
                std::memcpy(&fb, &b[f], 4);
                ADD_FAILURE() << "uniform (" << uniforms[2 * i] << ", " << uniforms[2 * i + 1]
                              << "): batched " << kField[f] << " "
                              << (f < 8 ? double(fa) : double(int32_t(a[f]))) << ", one by one "
                              << (f < 8 ? double(fb) : double(int32_t(b[f])));
            }
        }
    }
    for (int f = 0; f < 10; ++f)
        EXPECT_EQ(differ[f], 0) << kField[f] << ": batched samples differing from one-by-one ones";
    // For the record (docs/devices.md): how many of the device's values are not the host's bits
    // (allowed above within rounding; the renders compare whole images).
    size_t not_host = 0;
    for (size_t i = 0; i < dev.size(); ++i)
        not_host += std::memcmp(&dev[i], &host[i], sizeof(host[i])) != 0;
    std::printf("%s: %zu of %zu device samples differ from the host's in some bit\n", name.c_str(),
                not_host, dev.size());
}

TEST(EnvmapSampling, KernelMatchesHostSyntheticBlock) {
    // Lit in a block only, no blur: runs of zero-width cells in both CDFs.
    et::RgbImage img = ett::constant_image(40, 20, 0.0f);
    for (int y = 6; y < 11; ++y)
        for (int x = 3; x < 30; x += 3)
            img.at(x, y)[0] = img.at(x, y)[1] = img.at(x, y)[2] = float(x + y);
    et::DistributionOptions opt;
    opt.blur_sigma = 0.0f;
    compare_kernel_and_host("synthetic", et::make_envmap("synthetic", img, opt));
}

TEST(EnvmapSampling, KernelMatchesHostSyntheticRotatedOdd) {
    et::RgbImage img = ett::constant_image(37, 19, 0.0f);
    std::mt19937 rng(1);
    for (float& v : img.rgb)
        v = rng() % 4 == 0 ? std::ldexp(float(rng() % 100), -int(rng() % 20)) : 0.0f;
    ett::WarningCapture warnings; // not 2:1
    et::EnvMap env = et::make_envmap("odd", img, {});
    env.rotation_degrees = -121.0f;
    compare_kernel_and_host("odd-rotated", env);
}

TEST(EnvmapSampling, KernelMatchesHostGrace) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    compare_kernel_and_host("grace", ett::load_map(path));
}

TEST(EnvmapSampling, KernelMatchesHostRoyalEsplanade) {
    ETT_DATA_FILE(path, "envmaps/royal_esplanade_1k.hdr");
    et::EnvMap env = ett::load_map(path);
    env.rotation_degrees = 200.0f;
    compare_kernel_and_host("royal_esplanade", env);
}

TEST(EnvmapSampling, KernelMatchesHostPedestrianOverpassLowRes) {
    ETT_DATA_FILE(path, "envmaps/pedestrian_overpass_1k.hdr");
    et::DistributionOptions opt;
    opt.width = 256;
    opt.height = 100;
    compare_kernel_and_host("pedestrian_overpass", ett::load_map(path, opt));
}

TEST(EnvmapSampling, KernelMatchesHostMuseumWells) {
    ETT_DATA_FILE(path, "envmaps/museum_wells6.exr");
    compare_kernel_and_host("museum_wells6", ett::load_map(path));
}

TEST(EnvmapSampling, KernelMatchesHostBlackMap) {
    ett::WarningCapture warnings;
    compare_kernel_and_host("black", et::make_envmap("black", ett::constant_image(32, 16, 0), {}));
}

} // namespace
