// The solid-angle density etk_env_pdf: it integrates to one over the sphere, it equals the
// density returned with each sample the kernel draws, and no sample of a lit map has density 0.
#include "render/env_sampling.h"
#include "kernels/sampler.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

// Midpoint quadrature of etk_env_pdf over the sphere on a (theta, phi) grid of k x k points per
// distribution cell, each weighted by the exact solid angle of its patch, dphi * (cos theta0 -
// cos theta1). The grid follows the map's cells (shifted by the rotation, measured from
// etk_env_to_world), so no point sits on a density jump, and it has at least 512 rows, so the
// midpoint error of the 1 / sin theta shape within a patch, O(dtheta^2 / 24), stays below 2e-6.
double integrate_pdf(const et::EnvMap& env) {
    const int k = std::max(2, (512 + env.dist.height - 1) / env.dist.height);
    const etk::EtkEnvMap desc = env.desc();
    const etk::float3 c = etk::etk_env_to_world(desc, etk::make_float3(0, 0, -1));
    const double shift = std::atan2(c.x, -c.z);
    const int nt = env.dist.height * k, np = env.dist.width * k;
    double total = 0.0;
    for (int j = 0; j < nt; ++j) {
        const double t0 = M_PI * j / nt, t1 = M_PI * (j + 1) / nt, t = 0.5 * (t0 + t1);
        const double patch = (std::cos(t0) - std::cos(t1)) * 2 * M_PI / np;
        double row = 0.0;
        for (int i = 0; i < np; ++i) {
            const double p = -M_PI + 2 * M_PI * (i + 0.5) / np + shift;
            const etk::float3 d = etk::make_float3(static_cast<float>(std::sin(t) * std::sin(p)),
                                                   static_cast<float>(std::cos(t)),
                                                   static_cast<float>(-std::sin(t) * std::cos(p)));
            row += etk::etk_env_pdf(env.dist.table.data(), desc, d);
        }
        total += row * patch;
    }
    return total;
}

// Angular distance from direction d to the nearest edge of distribution cell (row, col), in
// radians (map space).
double distance_to_cell_edge(const et::EnvMap& env, const etk::float3& world, int row, int col) {
    const etk::float3 d = etk::etk_world_to_env(env.desc(), world);
    const double x = d.x, y = d.y, z = d.z;
    const double theta = std::atan2(std::sqrt(x * x + z * z), y), phi = std::atan2(x, -z);
    const double st = std::sin(theta);
    const double t0 = M_PI * row / env.dist.height, t1 = M_PI * (row + 1) / env.dist.height;
    const double p0 = -M_PI + 2 * M_PI * col / env.dist.width;
    const double p1 = -M_PI + 2 * M_PI * (col + 1) / env.dist.width;
    auto wrap = [](double a) { return std::fabs(std::remainder(a, 2 * M_PI)); };
    return std::min(
        {std::fabs(theta - t0), std::fabs(theta - t1), st * wrap(phi - p0), st * wrap(phi - p1)});
}

struct Case {
    std::string name;
    et::EnvMap env;
};

std::vector<Case> cases() {
    std::vector<Case> out;
    ett::WarningCapture quiet;
    et::RgbImage one = ett::constant_image(64, 32, 0.0f);
    one.at(20, 3)[1] = 100.0f;
    out.push_back({"one-lit-texel", et::make_envmap("one", one, {})});
    out.push_back({"constant", et::make_envmap("constant", ett::constant_image(64, 32, 2), {})});
    et::RgbImage two = ett::constant_image(2, 1, 1.0f);
    two.at(0, 0)[0] = 5.0f;
    out.push_back({"2x1", et::make_envmap("2x1", two, {})});
    out.push_back({"1x1", et::make_envmap("1x1", ett::constant_image(1, 1, 0.5f), {})});
    for (const char* name :
         {"grace.hdr", "royal_esplanade_1k.hdr", "pedestrian_overpass_1k.hdr", "spot1Lux.hdr"}) {
        const std::string path = ett::data_file(std::string("envmaps/") + name);
        if (!path.empty())
            out.push_back({name, ett::load_map(path)});
    }
    if (const std::string path = ett::data_file("envmaps/grace.hdr"); !path.empty()) {
        Case rotated{"grace-rotated", ett::load_map(path)};
        rotated.env.rotation_degrees = 33.0f;
        out.push_back(std::move(rotated));
        et::DistributionOptions low;
        low.width = 100;
        low.height = 30;
        out.push_back({"grace-100x30", ett::load_map(path, low)});
    }
    return out;
}

TEST(EnvmapPdf, IntegratesToOne) {
    for (const Case& c : cases())
        EXPECT_NEAR(integrate_pdf(c.env), 1.0, 1e-3) << c.name;
    if (ett::data_dir().empty())
        GTEST_SKIP() << "only synthetic maps tested: ../shared/data not found";
}

TEST(EnvmapPdf, BlackMapHasZeroDensityEverywhere) {
    ett::WarningCapture quiet;
    const et::EnvMap env = et::make_envmap("black", ett::constant_image(32, 16, 0.0f), {});
    EXPECT_EQ(integrate_pdf(env), 0.0);
}

TEST(EnvmapPdf, MatchesTheDensityReturnedWithEachSample) {
    const int n = 1 << 18;
    for (const Case& c : cases())
        for (int sampler : {ETK_SAMPLER_RANDOM, ETK_SAMPLER_SOBOL}) {
            SCOPED_TRACE(c.name + (sampler == ETK_SAMPLER_SOBOL ? " sobol" : " random"));
            et::EnvSamplerCL cl(ett::runtime(), c.env);
            const auto samples = cl.sample_sequence(sampler, 77u, 5u, 0u, n);
            const etk::EtkEnvMap desc = c.env.desc();
            size_t zero = 0, mismatched = 0, edge = 0;
            double worst = 0.0;
            for (const auto& s : samples) {
                if (!(s.pdf > 0.0f) || !std::isfinite(s.pdf)) {
                    ++zero;
                    continue;
                }
                const etk::float3 d = etk::make_float3(s.dir[0], s.dir[1], s.dir[2]);
                const float p = etk::etk_env_pdf(c.env.dist.table.data(), desc, d);
                // The density is proportional to 1 / sin theta: near the poles a float v (or
                // direction) one ulp off changes it by ~ ulp / sin theta, so the tolerance grows
                // there from 1e-4 by a few ulps of 1 over sin theta.
                const double st = std::sqrt(double(d.x) * d.x + double(d.z) * d.z);
                const double rel = std::fabs(p - s.pdf) / s.pdf;
                if (rel <= 1e-4 + 8 * 0x1p-24 / st)
                    continue;
                // Float rounding of the direction may carry a sample lying within a few ulps of a
                // cell edge across it: allowed when it is that close, and still has density.
                const double dist = distance_to_cell_edge(c.env, d, s.row, s.col);
                if (dist < 1e-5 && p > 0.0f) {
                    ++edge;
                } else {
                    ++mismatched;
                    worst = std::max(worst, rel);
                    if (mismatched <= 5)
                        ADD_FAILURE()
                            << "sample in cell (" << s.row << ", " << s.col << ") dir (" << d.x
                            << ", " << d.y << ", " << d.z << "): pdf " << s.pdf << " returned, "
                            << p << " evaluated, " << dist << " rad from the cell edge";
                }
            }
            EXPECT_EQ(zero, 0u) << "samples with density 0 or non-finite";
            EXPECT_EQ(mismatched, 0u) << "worst relative difference " << worst;
            EXPECT_LE(edge, n / 1000u) << "too many samples crossing cell edges";
            std::printf("%s: %zu of %d samples crossed a cell edge by rounding\n", c.name.c_str(),
                        edge, n);
        }
}

} // namespace
