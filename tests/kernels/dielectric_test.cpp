// The dielectric interfaces (kernels/dielectric.h, through etk_bsdf_*): chi-square goodness of
// fit of the rough interface's samples against its pdf over the whole sphere (reflection above,
// transmission below), from outside (eta = ior) and from inside (eta = 1 / ior, total internal
// reflection included), for both GGX samplings; the pdf's integral against the fraction of
// samples lost (reflected below or refracted above the macro-surface); the density and weight
// handed out with each sample; the generalised reciprocity of radiance BSDFs across an interface
// (f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2, Veach 1997 eq. 5.14); the smooth interface's Fresnel
// reflectance against the textbook formula in double precision, and its refraction against
// Snell's law.
//
// Grid: 64 bins in phi x 64 bins in theta over [0, pi] (the sphere), plus one cell for lost
// samples; expected counts by the adaptive midpoint rule of bsdf_test.cpp.
#include "chi2.h"
#include "kernels/bsdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>

namespace {

constexpr int kPhi = 64, kTheta = 64;
constexpr int kSamples = 1 << 20;

etk::EtkMaterial glass(float eta, float alpha, int vndf, bool smooth = false) {
    etk::EtkMaterial m;
    m.type = smooth ? ETK_MAT_SMOOTH_DIELECTRIC : ETK_MAT_DIELECTRIC;
    m.ggx_sampling = vndf;
    m.albedo = etk::make_float3(1, 1, 1);
    m.specular = etk::make_float3(0, 0, 0);
    m.alpha = alpha;
    m.eta = eta;
    return m;
}

struct Config {
    etk::EtkMaterial m;
    float cos_o;
};

std::vector<Config> configs() {
    std::vector<Config> c;
    for (float eta : {1.5f, 1.0f / 1.5f, 1.1f})
        for (float alpha : {0.05f, 0.25f, 0.7f})
            for (float cos_o : {0.95f, 0.5f, 0.1f})
                for (int vndf : {0, 1})
                    if (eta != 1.1f || (alpha == 0.25f && cos_o == 0.5f))
                        c.push_back({glass(eta, alpha, vndf), cos_o});
    return c;
}

etk::float3 wo_of(float cos_o) {
    const float s = std::sqrt(1 - cos_o * cos_o);
    return etk::make_float3(s * std::cos(0.3f), s * std::sin(0.3f), cos_o);
}

int bin_of(const etk::float3& w) {
    const double th = std::acos(std::clamp(double(w.z), -1.0, 1.0));
    double ph = std::atan2(double(w.y), double(w.x));
    if (ph < 0)
        ph += 2 * M_PI;
    const int it = std::min(kTheta - 1, int(th / M_PI * kTheta));
    const int ip = std::min(kPhi - 1, int(ph / (2 * M_PI) * kPhi));
    return it * kPhi + ip;
}

// Integral of pdf sin(theta) over theta in [th0, th1], bin ip in phi, by the n x n midpoint rule.
double bin_integral(const etk::EtkMaterial& m, etk::float3 wo, double th0, double th1, int ip,
                    int n) {
    const double dth = (th1 - th0) / n, dph = 2 * M_PI / kPhi / n;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const double th = th0 + (i + 0.5) * dth, st = std::sin(th), ct = std::cos(th);
        for (int j = 0; j < n; ++j) {
            const double ph = (ip * n + j + 0.5) * dph;
            sum += st * etk::etk_bsdf_pdf(m, wo,
                                          etk::make_float3(float(st * std::cos(ph)),
                                                           float(st * std::sin(ph)), float(ct)));
        }
    }
    return sum * dth * dph;
}

// Refined until two successive estimates agree (as in bsdf_test.cpp).
double refined_integral(const etk::EtkMaterial& m, etk::float3 wo, double th0, double th1, int ip) {
    double prev = bin_integral(m, wo, th0, th1, ip, 4), cur = prev;
    for (int n = 8; n <= 512; n *= 2) {
        cur = bin_integral(m, wo, th0, th1, ip, n);
        if (std::fabs(cur - prev) <= std::max(1e-4 * cur, 0.01 / kSamples))
            break;
        prev = cur;
    }
    return cur;
}

// The transmission's pdf jumps at wi.z = -wo.z / eta, where the half vector reaches the horizon
// (h.z = 0): beyond it no microfacet refracts wo into wi, and with visible-normal sampling the
// density just inside is not small. A bin holding the jump is integrated in two parts, split
// there, or a midpoint rule converges to 0 on a bin whose support is a sliver at its edge.
std::vector<double> integrate_pdf(const etk::EtkMaterial& m, etk::float3 wo) {
    std::vector<double> p(kPhi * kTheta, 0.0);
    const double z_jump = -wo.z / m.eta;
    const double th_jump = z_jump > -1.0 ? std::acos(z_jump) : -1.0;
    for (int it = 0; it < kTheta; ++it) {
        const double th0 = M_PI * it / kTheta, th1 = M_PI * (it + 1) / kTheta;
        const bool split = th_jump > th0 && th_jump < th1;
        for (int ip = 0; ip < kPhi; ++ip)
            p[it * kPhi + ip] = split ? refined_integral(m, wo, th0, th_jump, ip) +
                                            refined_integral(m, wo, th_jump, th1, ip)
                                      : refined_integral(m, wo, th0, th1, ip);
    }
    return p;
}

std::string label_of(const Config& c) {
    std::ostringstream s;
    s << "eta " << c.m.eta << " alpha " << c.m.alpha << " cos(theta_o) " << c.cos_o
      << (c.m.ggx_sampling ? " vndf" : " ndf");
    return s.str();
}

TEST(Dielectric, RoughSamplingMatchesPdfChiSquareOverTheSphere) {
    const std::vector<Config> cs = configs();
    const double alpha = ett::sidak_alpha(0.01, static_cast<int>(cs.size()));
    std::mt19937 rng(314);
    std::uniform_real_distribution<float> U(0.0f, 0.99999994f);
    for (const Config& c : cs) {
        const etk::float3 wo = wo_of(c.cos_o);
        const std::string label = label_of(c);
        SCOPED_TRACE(label);
        std::vector<double> observed(kPhi * kTheta + 1, 0.0);
        int lost = 0, transmitted = 0;
        for (int k = 0; k < kSamples; ++k) {
            const etk::float2 u = etk::make_float2(U(rng), U(rng));
            const etk::EtkBsdfSample s = etk::etk_bsdf_sample(c.m, wo, u, U(rng));
            if (!(s.pdf > 0.0f)) {
                ++lost;
                continue;
            }
            ASSERT_EQ(s.delta, 0);
            ASSERT_NE(s.wi.z, 0.0f);
            ASSERT_NEAR(std::sqrt(etk::dot(s.wi, s.wi)), 1.0f, 1e-5f);
            const float pdf = etk::etk_bsdf_pdf(c.m, wo, s.wi);
            ASSERT_NEAR(s.pdf, pdf, 2e-4f * pdf) << "wi.z " << s.wi.z;
            const float w = etk::etk_bsdf_eval(c.m, wo, s.wi).x * std::fabs(s.wi.z) / pdf;
            ASSERT_NEAR(s.weight.x, w, 2e-4f * w + 1e-7f) << "wi.z " << s.wi.z;
            transmitted += s.wi.z < 0;
            observed[bin_of(s.wi)] += 1.0;
        }
        observed[kPhi * kTheta] = lost;
        const std::vector<double> prob = integrate_pdf(c.m, wo);
        std::vector<double> expected(kPhi * kTheta + 1, 0.0);
        double total = 0.0, below = 0.0;
        for (int i = 0; i < kPhi * kTheta; ++i) {
            expected[i] = prob[i] * kSamples;
            total += prob[i];
            below += i >= kPhi * kTheta / 2 ? prob[i] : 0.0;
        }
        expected[kPhi * kTheta] = std::max(0.0, 1.0 - total) * kSamples;
        const double lost_fraction = double(lost) / kSamples;
        EXPECT_LE(total, 1.0 + 2e-4);
        EXPECT_NEAR(1.0 - total, lost_fraction,
                    5 * std::sqrt(std::max(lost_fraction, 1e-6) / kSamples) + 2e-4)
            << "pdf integral " << total << ", lost " << lost_fraction;
        if (c.m.eta > 1.0f || c.cos_o > 0.9f) {     // else mostly total internal reflection
            EXPECT_GT(transmitted, kSamples / 100); // both hemispheres were exercised
        }
        // The lobe's support can end inside a cell, where the quadrature may find no mass while
        // a sample lands in the sliver (seen with clang's rounding: 1 of 2^20). A sampler that
        // really leaves its pdf's support puts far more there than 2.
        const ett::Chi2Result r =
            ett::chi2_test(observed, expected, kPhi, kTheta + 1, alpha, 5.0, 2.0);
        if (!r.passed)
            ett::dump_histograms("dielectric-chi2", observed, expected, kPhi, kTheta + 1);
        EXPECT_TRUE(r.passed) << r.report;
        std::printf("%-40s pdf integral %.5f (below %.4f), lost %.5f, chi2 p = %.3g (dof %d)\n",
                    label.c_str(), total, below, lost_fraction, r.p_value, r.dof);
    }
}

// Across an interface, f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2 for the radiance BSDF: seen from
// wi's side (the frame flipped: z -> -z) the relative index is 1 / eta, so
// f(eta; wo, wi) eta^2 = f(1 / eta; wi', wo'). Reflection is plainly symmetric.
TEST(Dielectric, GeneralisedReciprocity) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    auto dir = [&](float sign) {
        const float z = std::max(1e-2f, U(rng)), s = std::sqrt(1 - z * z),
                    ph = 2 * float(M_PI) * U(rng);
        return etk::make_float3(s * std::cos(ph), s * std::sin(ph), sign * z);
    };
    auto flip = [](etk::float3 v) { return etk::make_float3(v.x, v.y, -v.z); };
    int nonzero = 0;
    for (float eta : {1.5f, 1.0f / 1.33f, 2.4f})
        for (float alpha : {0.1f, 0.4f, 0.9f})
            for (int k = 0; k < 20000; ++k) {
                const etk::float3 wo = dir(1.0f), wt = dir(-1.0f), wr = dir(1.0f);
                const float ft = etk::etk_bsdf_eval(glass(eta, alpha, 1), wo, wt).x;
                const float bt = etk::etk_bsdf_eval(glass(1 / eta, alpha, 1), flip(wt), flip(wo)).x;
                ASSERT_TRUE(std::isfinite(ft) && ft >= 0.0f);
                // Near the critical angle (grazing on the outer side of the microfacet, cosine
                // c) the two sides' Fresnel terms come from cosines that carry float rounding
                // ~1e-7, amplified by n^2 / c^2 through Snell's law: the tolerance follows.
                int ok;
                const etk::float3 h = etk::etk_dielectric_half_t(wo, wt, eta, &ok);
                const float c = eta > 1.0f ? etk::dot(wo, h) : -etk::dot(wt, h);
                const float n2 = std::max(eta * eta, 1 / (eta * eta));
                const float tol = 1e-3f + (ok ? 4e-7f * n2 / (c * c) : 0.0f);
                ASSERT_NEAR(ft * eta * eta, bt, tol * std::max(ft * eta * eta, bt) + 1e-9f)
                    << "eta " << eta << " alpha " << alpha;
                nonzero += ft > 0.0f;
                const float fr = etk::etk_bsdf_eval(glass(eta, alpha, 1), wo, wr).x;
                const float br = etk::etk_bsdf_eval(glass(eta, alpha, 1), wr, wo).x;
                const float cond = 1.0f + 1.0f / etk::length(wo + wr);
                ASSERT_NEAR(fr, br, 1e-4f * cond * std::max(fr, br) + 1e-9f);
            }
    EXPECT_GT(nonzero, 10000); // the check saw transmission, not only zeros
}

// Unpolarised Fresnel reflectance from the angles, in double precision (Born & Wolf).
double fresnel_reference(double cos_i, double n1, double n2) {
    const double sin_i = std::sqrt(std::max(0.0, 1 - cos_i * cos_i));
    const double sin_t = n1 / n2 * sin_i;
    if (sin_t >= 1)
        return 1.0;
    const double cos_t = std::sqrt(1 - sin_t * sin_t);
    const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

TEST(Dielectric, SmoothFresnelAndSnell) {
    // Known values: 4% at normal incidence for n = 1.5; at Brewster's angle only the s part.
    EXPECT_NEAR(etk::etk_fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-6f);
    const double brewster = std::atan(1.5);
    const double rs_b = fresnel_reference(std::cos(brewster), 1.0, 1.5) * 2;
    EXPECT_NEAR(etk::etk_fresnel_dielectric(float(std::cos(brewster)), 1.5f), rs_b / 2, 1e-5);
    // Beyond the critical angle from inside: total internal reflection.
    const float cos_crit = std::sqrt(1 - 1 / (1.5f * 1.5f));
    EXPECT_EQ(etk::etk_fresnel_dielectric(cos_crit * 0.99f, 1 / 1.5f), 1.0f);
    EXPECT_LT(etk::etk_fresnel_dielectric(cos_crit * 1.01f, 1 / 1.5f), 1.0f);
    for (double n2 : {1.2, 1.5, 2.4})
        for (bool inside : {false, true})
            for (int k = 0; k <= 100; ++k) {
                const double cos_i = k / 100.0;
                const double n_o = inside ? n2 : 1.0, n_t = inside ? 1.0 : n2;
                const float eta = float(n_t / n_o);
                const double ref = fresnel_reference(cos_i, n_o, n_t);
                ASSERT_NEAR(etk::etk_fresnel_dielectric(float(cos_i), eta), ref, 2e-6)
                    << "n " << n2 << (inside ? " inside" : " outside") << " cos " << cos_i;
                if (k == 0)
                    continue;
                // The smooth interface's two branches: reflection with probability F (the
                // branch is chosen by `lobe`), refraction by Snell's law with weight 1 / eta^2.
                const etk::EtkMaterial m = glass(eta, 0.0f, 0, true);
                const float sin_i = float(std::sqrt(1 - cos_i * cos_i));
                const etk::float3 wo = etk::make_float3(sin_i * 0.6f, sin_i * 0.8f, float(cos_i));
                const float f = etk::etk_fresnel_dielectric(float(cos_i), eta);
                const etk::EtkBsdfSample r =
                    etk::etk_bsdf_sample(m, wo, etk::make_float2(0.5f, 0.5f), f * 0.999f);
                const etk::EtkBsdfSample t =
                    etk::etk_bsdf_sample(m, wo, etk::make_float2(0.5f, 0.5f), f + (1 - f) * 0.5f);
                if (f > 0.0f) {
                    ASSERT_EQ(r.delta, 1);
                    EXPECT_NEAR(r.pdf, f, 1e-6f);
                    EXPECT_FLOAT_EQ(r.wi.z, wo.z);
                    EXPECT_FLOAT_EQ(r.weight.x, 1.0f);
                }
                if (f >= 1.0f)
                    continue;
                ASSERT_EQ(t.delta, 1);
                EXPECT_NEAR(t.pdf, 1 - f, 1e-6f);
                ASSERT_LT(t.wi.z, 0.0f);
                const double sin_t = std::sqrt(t.wi.x * t.wi.x + t.wi.y * t.wi.y);
                EXPECT_NEAR(n_t * sin_t, n_o * sin_i, 2e-6 * n2);      // Snell
                EXPECT_NEAR(t.wi.x * wo.y - t.wi.y * wo.x, 0.0, 1e-6); // plane of incidence
                EXPECT_LE(t.wi.x * wo.x + t.wi.y * wo.y, 1e-7);        // the far side
                EXPECT_NEAR(t.weight.x, 1.0f / (eta * eta), 1e-6f / (eta * eta));
            }
    // Both evaluate to zero (delta lobes) and are delta to the integrator.
    const etk::EtkMaterial s = glass(1.5f, 0.0f, 0, true);
    EXPECT_TRUE(etk::etk_bsdf_is_delta(s));
    EXPECT_EQ(etk::etk_bsdf_pdf(s, wo_of(0.5f), etk::make_float3(0, 0, -1)), 0.0f);
}

// At eta = 1 a rough interface refracts nothing: every microfacet passes wo straight on, so it
// is a delta transmission of weight 1 (the object is invisible) rather than a GGX lobe.
TEST(Dielectric, RoughIndexOneIsAStraightPassage) {
    const etk::EtkMaterial m = glass(1.0f, 0.4f, 1);
    EXPECT_TRUE(etk::etk_bsdf_is_delta(m));
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> U(0.0f, 0.99999994f);
    for (int k = 0; k < 1000; ++k) {
        const etk::float3 wo = wo_of(std::max(0.01f, U(rng)));
        const etk::EtkBsdfSample s =
            etk::etk_bsdf_sample(m, wo, etk::make_float2(U(rng), U(rng)), U(rng));
        ASSERT_EQ(s.delta, 1);
        EXPECT_FLOAT_EQ(s.wi.x, -wo.x);
        EXPECT_FLOAT_EQ(s.wi.z, -wo.z);
        EXPECT_FLOAT_EQ(s.weight.x, 1.0f);
    }
}

// Without the radiance scaling, a lossless interface scatters at most what arrives: the mean of
// the sample weights (transmissions times eta^2) is at most 1, and for a smooth interface
// exactly 1. Rough ones lose what single-scattering GGX loses to masking (light that would
// scatter again among the microfacets), most at grazing angles and high roughness.
TEST(Dielectric, EnergyAtMostOne) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> U(0.0f, 0.99999994f);
    const int n = 1 << 18;
    for (float eta : {1.5f, 1.0f / 1.5f})
        for (float alpha : {0.0f, 0.05f, 0.3f, 0.8f})
            for (float cos_o : {1.0f, 0.5f, 0.1f}) {
                const etk::EtkMaterial m = glass(eta, std::max(alpha, 1e-3f), 1, alpha == 0.0f);
                const etk::float3 wo = wo_of(cos_o);
                double sum = 0.0, sum2 = 0.0;
                for (int k = 0; k < n; ++k) {
                    const etk::EtkBsdfSample s =
                        etk::etk_bsdf_sample(m, wo, etk::make_float2(U(rng), U(rng)), U(rng));
                    const double w =
                        s.pdf > 0 ? s.weight.x * (s.wi.z < 0 ? double(eta) * eta : 1.0) : 0.0;
                    sum += w;
                    sum2 += w * w;
                }
                const double mc = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - mc * mc) / n);
                SCOPED_TRACE(::testing::Message() << "eta " << eta << " alpha " << alpha << " cos "
                                                  << cos_o << ": " << mc << " +- " << sd);
                EXPECT_LE(mc, 1.0 + 5 * sd + 1e-5);
                if (alpha == 0.0f) {
                    EXPECT_NEAR(mc, 1.0, 1e-5);
                } else if (alpha == 0.05f && cos_o >= 0.5f) {
                    EXPECT_GT(mc, 0.97); // a nearly smooth interface loses little
                }
                std::printf("eta %.3f alpha %.2f cos(theta_o) %.1f: energy %.4f +- %.4f\n", eta,
                            alpha, cos_o, mc, sd);
            }
}

} // namespace
