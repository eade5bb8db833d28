// Chi-square goodness of fit of the directions the OpenCL sampling kernel draws against the
// solid-angle density etk_env_pdf, in the style of Mitsuba 3's chi2.py.
//
// Samples are binned on an equal-area grid over (phi, cos theta) in world space. Expected counts
// are exact: within one distribution cell (row r, column c) the density is p(omega) = K / sin
// theta (piecewise constant in the lat-long square, divided by the Jacobian), so with d omega =
// sin theta d theta d phi the probability of any (theta, phi) rectangle inside the cell is
// K * d theta * d phi, and a (phi, cos theta) bin is such a rectangle. K is measured by calling
// etk_env_pdf at the world direction of the cell centre and multiplying by sin theta there; the
// integral over a bin is then a bilinear lookup into a summed-area table of K. Integrating
// etk_env_pdf numerically instead would add quadrature error at the many density jumps of maps
// like grace.hdr, whose sun covers a handful of cells.
#include "chi2.h"
#include "prepare/env_compensation.h"
#include "render/env_sampling.h"
#include "kernels/sampler.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

constexpr int kPhiBins = 128, kCosBins = 64;
constexpr int kSamples = 1 << 20;
// Every chi-square test of this file shares the family-wise alpha of 0.01.
constexpr int kChi2Tests = 14;

// The world-space azimuth used for binning (the lat-long convention of ../shared/data/README.md).
double world_phi(double x, double z) {
    return std::atan2(x, -z);
}

// Exact probability of world-space (phi, cos theta) bins under etk_env_pdf.
class ExactBinIntegrator {
  public:
    explicit ExactBinIntegrator(const et::EnvMap& env) : w_(env.dist.width), h_(env.dist.height) {
        const etk::EtkEnvMap desc = env.desc();
        // Where the map's centre direction (-Z in map space) lands in world space: the
        // rotation about the up axis is a shift of phi by this amount.
        const etk::float3 c = etk::etk_env_to_world(desc, etk::make_float3(0, 0, -1));
        shift_ = world_phi(c.x, c.z);
        const double dtheta = M_PI / h_, dphi = 2 * M_PI / w_;
        sat_.assign(static_cast<size_t>(w_ + 1) * (h_ + 1), 0.0);
        for (int r = 0; r < h_; ++r) {
            const double theta = (r + 0.5) * dtheta;
            double row = 0.0;
            for (int col = 0; col < w_; ++col) {
                const double phi = -M_PI + (col + 0.5) * dphi + shift_;
                const etk::float3 d =
                    etk::make_float3(static_cast<float>(std::sin(theta) * std::sin(phi)),
                                     static_cast<float>(std::cos(theta)),
                                     static_cast<float>(-std::sin(theta) * std::cos(phi)));
                const double k = etk::etk_env_pdf(env.dist.table.data(), desc, d) * std::sin(theta);
                row += k * dtheta * dphi;
                at(r + 1, col + 1) = at(r, col + 1) + row;
            }
        }
    }

    // Probability of the world-space bin theta in [t0, t1], phi in [p0, p1] (p0 < p1, width <=
    // 2 pi).
    double bin(double t0, double t1, double p0, double p1) const {
        double a = p0 - shift_;
        a -= 2 * M_PI * std::floor((a + M_PI) / (2 * M_PI)); // into [-pi, pi)
        const double b = a + (p1 - p0);
        if (b <= M_PI)
            return rect(t0, t1, a, b);
        return rect(t0, t1, a, M_PI) + rect(t0, t1, -M_PI, b - 2 * M_PI);
    }

    double total() const { return F(M_PI, M_PI); }

  private:
    double& at(int r, int c) { return sat_[static_cast<size_t>(r) * (w_ + 1) + c]; }
    double at(int r, int c) const { return sat_[static_cast<size_t>(r) * (w_ + 1) + c]; }
    // Integral over theta in [0, t], map-space phi in [-pi, p]: bilinear in the table.
    double F(double t, double p) const {
        const double y = std::clamp(t / M_PI * h_, 0.0, double(h_));
        const double x = std::clamp((p + M_PI) / (2 * M_PI) * w_, 0.0, double(w_));
        const int r = std::min(static_cast<int>(y), h_ - 1),
                  c = std::min(static_cast<int>(x), w_ - 1);
        const double fy = y - r, fx = x - c;
        return (1 - fy) * ((1 - fx) * at(r, c) + fx * at(r, c + 1)) +
               fy * ((1 - fx) * at(r + 1, c) + fx * at(r + 1, c + 1));
    }
    double rect(double t0, double t1, double p0, double p1) const {
        return F(t1, p1) - F(t0, p1) - F(t1, p0) + F(t0, p0);
    }
    int w_, h_;
    double shift_ = 0.0;
    std::vector<double> sat_;
};

void run_chi2(const std::string& name, const et::EnvMap& env, int sampler = ETK_SAMPLER_RANDOM) {
    ASSERT_TRUE(env.dist.has_light());
    et::EnvSamplerCL cl(ett::runtime(), env);
    const auto samples = cl.sample_sequence(sampler, 20240611u, 3u, 0u, kSamples);

    std::vector<double> observed(kPhiBins * kCosBins, 0.0);
    std::vector<std::pair<double, double>> coords; // (phi, cos theta) of each valid sample
    size_t bad = 0;
    for (const auto& s : samples) {
        if (!(s.pdf > 0.0f) || !std::isfinite(s.pdf) || !std::isfinite(s.dir[0]) ||
            !std::isfinite(s.dir[1]) || !std::isfinite(s.dir[2])) {
            ++bad;
            continue;
        }
        coords.emplace_back(world_phi(s.dir[0], s.dir[2]), s.dir[1]);
    }
    EXPECT_EQ(bad, 0u) << name << ": samples with zero or non-finite pdf or direction";

    ExactBinIntegrator integ(env);
    EXPECT_NEAR(integ.total(), 1.0, 1e-4) << name << ": the pdf does not integrate to one";
    std::vector<double> expected(observed.size());
    for (int j = 0; j < kCosBins; ++j) {
        const double t0 = std::acos(1.0 - 2.0 * j / kCosBins);
        const double t1 = std::acos(std::max(-1.0, 1.0 - 2.0 * (j + 1) / kCosBins));
        for (int i = 0; i < kPhiBins; ++i) {
            const double p0 = -M_PI + 2 * M_PI * i / kPhiBins;
            const double p1 = -M_PI + 2 * M_PI * (i + 1) / kPhiBins;
            // Clamp tiny negative round-off of the table differences.
            expected[j * kPhiBins + i] = std::max(0.0, integ.bin(t0, t1, p0, p1)) * kSamples;
        }
    }
    // A bin the density never reaches must not get rounding residue from the table.
    for (double& e : expected)
        if (e < 1e-9)
            e = 0.0;

    // Bin the samples. A sample drawn within a float step of a cell edge can round across it
    // (the direction is stored in float: ~1e-7 rad); a sample that lands in a bin the density
    // never reaches but lies within kEdge of a reachable neighbour is counted there, and such
    // edge crossings must stay rare. Anything farther is a real zero-cell hit and fails.
    const double kEdge = 1e-6;
    size_t edge_crossings = 0;
    auto bin_of = [](double phi, double y) {
        const int i =
            std::clamp(static_cast<int>((phi + M_PI) / (2 * M_PI) * kPhiBins), 0, kPhiBins - 1);
        const int j = std::clamp(static_cast<int>((1.0 - y) / 2.0 * kCosBins), 0, kCosBins - 1);
        return j * kPhiBins + i;
    };
    for (const auto& [phi, y] : coords) {
        int b = bin_of(phi, y);
        if (expected[b] == 0.0) {
            for (double dp : {-kEdge, kEdge, 0.0})
                for (double dy : {-kEdge, kEdge, 0.0}) {
                    double p2 = phi + dp;
                    p2 = p2 > M_PI ? p2 - 2 * M_PI : (p2 < -M_PI ? p2 + 2 * M_PI : p2);
                    const int b2 = bin_of(p2, y + dy);
                    if (expected[b] == 0.0 && expected[b2] > 0.0) {
                        b = b2;
                        ++edge_crossings;
                    }
                }
        }
        observed[b] += 1.0;
    }
    EXPECT_LE(edge_crossings, kSamples / 100000) << name << ": too many samples across cell edges";

    const ett::Chi2Result r =
        ett::chi2_test(observed, expected, kPhiBins, kCosBins, ett::sidak_alpha(0.01, kChi2Tests));
    if (!r.passed) {
        const std::string dump = ett::dump_histograms(name, observed, expected, kPhiBins, kCosBins);
        ADD_FAILURE() << name << ": " << r.report
                      << "\nhistograms (observed, expected, residual): " << dump;
    } else {
        std::printf("%s: %s\n", name.c_str(), r.report.substr(0, r.report.find('\n')).c_str());
    }
}

et::EnvMap data_map(const std::string& path, et::DistributionOptions opt = {}) {
    return ett::load_map(path, opt);
}

TEST(EnvmapChi2, Grace) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    run_chi2("grace", data_map(path));
}

TEST(EnvmapChi2, GraceSobol) {
    // The (0,2)-sequence is more uniform than independent samples, so its chi-square statistic is
    // smaller than the test assumes: still a valid check that nothing lands where it should not.
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    run_chi2("grace-sobol", data_map(path), ETK_SAMPLER_SOBOL);
}

TEST(EnvmapChi2, RoyalEsplanade) {
    ETT_DATA_FILE(path, "envmaps/royal_esplanade_1k.hdr");
    run_chi2("royal_esplanade", data_map(path));
}

TEST(EnvmapChi2, PedestrianOverpass) {
    ETT_DATA_FILE(path, "envmaps/pedestrian_overpass_1k.hdr");
    run_chi2("pedestrian_overpass", data_map(path));
}

TEST(EnvmapChi2, GraceRotated) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    et::EnvMap env = data_map(path);
    env.rotation_degrees = 73.3f;
    run_chi2("grace-rotated", env);
}

TEST(EnvmapChi2, RoyalEsplanadeLowDistributionResolution) {
    // 300x150 does not divide 1024x512: cells straddle texels.
    ETT_DATA_FILE(path, "envmaps/royal_esplanade_1k.hdr");
    et::DistributionOptions opt;
    opt.width = 300;
    opt.height = 150;
    const et::EnvMap env = data_map(path, opt);
    ASSERT_EQ(env.dist.width, 300);
    run_chi2("royal_esplanade-300x150", env);
}

TEST(EnvmapChi2, OneLitTexel) {
    et::RgbImage img = ett::constant_image(64, 32, 0.0f);
    float* t = img.at(41, 9);
    t[0] = t[1] = t[2] = 50.0f;
    run_chi2("one-lit-texel", et::make_envmap("one-lit-texel", img, {}));
}

TEST(EnvmapChi2, OneLitTexelNoBlur) {
    et::RgbImage img = ett::constant_image(64, 32, 0.0f);
    float* t = img.at(0, 31); // on the seam, next to the lower pole
    t[0] = t[1] = t[2] = 50.0f;
    et::DistributionOptions opt;
    opt.blur_sigma = 0.0f;
    run_chi2("one-lit-texel-seam", et::make_envmap("one-lit-texel-seam", img, opt));
}

// A map in Blender's lat-long convention (a quarter turn folded into the map-to-world rotation,
// load/environment_map.h), turned further by "rotation": the texel at u = 0.24 lands across the
// world's phi = +-pi seam.
TEST(EnvmapChi2, OneLitTexelBlenderConvention) {
    et::RgbImage img = ett::constant_image(64, 32, 0.0f);
    float* t = img.at(15, 12);
    t[0] = t[1] = t[2] = 50.0f;
    et::EnvMap env = et::make_envmap("one-lit-texel-blender", img, {});
    env.convention = et::LatLongConvention::blender;
    env.rotation_degrees = 3.0f;
    run_chi2("one-lit-texel-blender", env);
}

// The compensated distribution (prepare/env_compensation.h) is sampled by the same code from its
// own table: its samples against its own pdf, which must integrate to one.
et::EnvMap compensated(et::EnvMap env) {
    env.dist = et::compensate_distribution(env.dist);
    return env;
}

TEST(EnvmapChi2, GraceCompensated) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    run_chi2("grace-compensated", compensated(data_map(path)));
}

TEST(EnvmapChi2, RoyalEsplanadeCompensated) {
    ETT_DATA_FILE(path, "envmaps/royal_esplanade_1k.hdr");
    run_chi2("royal_esplanade-compensated", compensated(data_map(path)));
}

TEST(EnvmapChi2, PedestrianOverpassCompensatedRotated) {
    ETT_DATA_FILE(path, "envmaps/pedestrian_overpass_1k.hdr");
    et::EnvMap env = compensated(data_map(path));
    env.rotation_degrees = -41.0f;
    run_chi2("pedestrian_overpass-compensated-rotated", env);
}

TEST(EnvmapChi2, Constant) {
    run_chi2("constant", et::make_envmap("constant", ett::constant_image(64, 32, 1.0f), {}));
}

TEST(EnvmapChi2, TwoByOne) {
    et::RgbImage img = ett::constant_image(2, 1, 1.0f);
    img.at(1, 0)[0] = img.at(1, 0)[1] = img.at(1, 0)[2] = 3.0f;
    run_chi2("2x1", et::make_envmap("2x1", img, {}));
}

// The harness must be able to fail: uniform directions tested against grace's density.
TEST(EnvmapChi2, HarnessRejectsWrongDistribution) {
    et::EnvMap flat = et::make_envmap("constant", ett::constant_image(64, 32, 1.0f), {});
    et::RgbImage img = ett::constant_image(64, 32, 1.0f);
    img.at(10, 10)[1] = 30.0f; // a bright spot the samples below ignore
    et::EnvMap spot = et::make_envmap("spot", img, {});
    et::EnvSamplerCL cl(ett::runtime(), flat);
    const auto samples = cl.sample_sequence(ETK_SAMPLER_RANDOM, 7u, 0u, 0u, 1 << 18);
    ExactBinIntegrator integ(spot);
    std::vector<double> observed(kPhiBins * kCosBins, 0.0), expected(observed.size());
    for (const auto& s : samples) {
        const double phi = world_phi(s.dir[0], s.dir[2]);
        const int i =
            std::clamp(static_cast<int>((phi + M_PI) / (2 * M_PI) * kPhiBins), 0, kPhiBins - 1);
        const int j =
            std::clamp(static_cast<int>((1.0 - s.dir[1]) / 2.0 * kCosBins), 0, kCosBins - 1);
        observed[j * kPhiBins + i] += 1.0;
    }
    for (int j = 0; j < kCosBins; ++j)
        for (int i = 0; i < kPhiBins; ++i)
            expected[j * kPhiBins + i] =
                integ.bin(std::acos(1.0 - 2.0 * j / kCosBins),
                          std::acos(std::max(-1.0, 1.0 - 2.0 * (j + 1) / kCosBins)),
                          -M_PI + 2 * M_PI * i / kPhiBins, -M_PI + 2 * M_PI * (i + 1) / kPhiBins) *
                (1 << 18);
    const ett::Chi2Result r = ett::chi2_test(observed, expected, kPhiBins, kCosBins, 0.01);
    EXPECT_FALSE(r.passed) << r.report;
}

} // namespace
