// BSDF sampling and evaluation (kernels/bsdf.h): chi-square goodness of fit of etk_bsdf_sample's
// directions against etk_bsdf_pdf (the harness of tests/chi2.h, as for the environment map),
// the pdf's integral against the fraction of samples lost below the horizon, the density and
// weight returned with each sample, and reciprocity of etk_bsdf_eval.
//
// Grid: 64 bins in phi x 32 bins in theta over the upper hemisphere, plus one cell for samples
// returned with pdf 0 (lost below the horizon). theta bins rather than equal-area cos(theta)
// bins: at normal incidence a roughness-0.05 lobe is ~0.1 rad wide and would sit entirely in the
// first cos(theta) bin. The expected count of a bin is N times the integral of etk_bsdf_pdf
// sin(theta) over it (an adaptive midpoint rule, below); the lost cell expects N (1 - total).
#include "chi2.h"
#include "kernels/bsdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>

namespace {

constexpr int kPhi = 64, kTheta = 32;
constexpr int kSamples = 1 << 20;

struct Config {
    const char* name;
    etk::EtkMaterial m;
    float cos_o;
};

etk::EtkMaterial material(int type, float albedo, float f0, float alpha, int vndf = 0) {
    etk::EtkMaterial m;
    m.type = type;
    m.ggx_sampling = vndf;
    m.albedo = etk::make_float3(albedo, albedo, albedo);
    m.specular = etk::make_float3(f0, f0, f0);
    m.alpha = alpha;
    return m;
}

// Gold (eta and k in albedo's and F0's places, bsdf.h).
etk::EtkMaterial conductor(float alpha, int vndf) {
    etk::EtkMaterial m = material(ETK_MAT_CONDUCTOR, 0.0f, 0.0f, alpha, vndf);
    m.albedo = etk::make_float3(0.143f, 0.375f, 1.442f);
    m.specular = etk::make_float3(3.983f, 2.386f, 1.603f);
    return m;
}

std::vector<Config> configs() {
    std::vector<Config> c;
    for (float cos_o : {1.0f, 0.6f, 0.2f, 0.05f}) {
        c.push_back({"diffuse", material(ETK_MAT_DIFFUSE, 0.8f, 0.0f, 0.3f), cos_o});
        for (float alpha : {0.05f, 0.2f, 0.5f, 1.0f}) {
            c.push_back({"microfacet", material(ETK_MAT_MICROFACET, 0.0f, 0.9f, alpha), cos_o});
            c.push_back({"plastic", material(ETK_MAT_MICROFACET, 0.5f, 0.04f, alpha), cos_o});
            // Visible-normal sampling of the GGX lobe (Heitz 2018), with its own pdf.
            c.push_back(
                {"microfacet vndf", material(ETK_MAT_MICROFACET, 0.0f, 0.9f, alpha, 1), cos_o});
            c.push_back(
                {"plastic vndf", material(ETK_MAT_MICROFACET, 0.5f, 0.04f, alpha, 1), cos_o});
        }
        for (float alpha : {0.05f, 0.5f})
            for (int vndf : {ETK_GGX_NDF, ETK_GGX_VNDF})
                c.push_back({vndf ? "conductor vndf" : "conductor", conductor(alpha, vndf), cos_o});
    }
    return c;
}

etk::float3 wo_of(float cos_o) {
    // Azimuth 0.3 rad: nothing special about phi = 0.
    const float s = std::sqrt(1 - cos_o * cos_o);
    return etk::make_float3(s * std::cos(0.3f), s * std::sin(0.3f), cos_o);
}

int bin_of(const etk::float3& w) {
    const double th = std::acos(std::clamp(double(w.z), -1.0, 1.0));
    double ph = std::atan2(double(w.y), double(w.x));
    if (ph < 0)
        ph += 2 * M_PI;
    const int it = std::min(kTheta - 1, int(th / (M_PI / 2) * kTheta));
    const int ip = std::min(kPhi - 1, int(ph / (2 * M_PI) * kPhi));
    return it * kPhi + ip;
}

// Integral of pdf sin(theta) over bin (it, ip) by the n x n midpoint rule.
double bin_integral(const etk::EtkMaterial& m, etk::float3 wo, int it, int ip, int n) {
    const double dth = M_PI / 2 / kTheta / n, dph = 2 * M_PI / kPhi / n;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const double th = (it * n + i + 0.5) * dth, st = std::sin(th), ct = std::cos(th);
        for (int j = 0; j < n; ++j) {
            const double ph = (ip * n + j + 0.5) * dph;
            sum += st * etk::etk_bsdf_pdf(m, wo,
                                          etk::make_float3(float(st * std::cos(ph)),
                                                           float(st * std::sin(ph)), float(ct)));
        }
    }
    return sum * dth * dph;
}

// Integral of the pdf (solid angle) over each bin: the midpoint rule refined (8, 16, ... 512
// points a side) until two successive estimates agree within 1e-4 relative or 0.01 of an
// expected sample. Near grazing incidence the lowest-roughness lobe is squeezed against the
// horizon to a few thousandths of a radian, so a fixed rule is not enough there.
std::vector<double> integrate_pdf(const etk::EtkMaterial& m, etk::float3 wo) {
    std::vector<double> p(kPhi * kTheta, 0.0);
    for (int it = 0; it < kTheta; ++it)
        for (int ip = 0; ip < kPhi; ++ip) {
            double prev = bin_integral(m, wo, it, ip, 8), cur = prev;
            for (int n = 16; n <= 512; n *= 2) {
                cur = bin_integral(m, wo, it, ip, n);
                if (std::fabs(cur - prev) <= std::max(1e-4 * cur, 0.01 / kSamples))
                    break;
                prev = cur;
            }
            p[it * kPhi + ip] = cur;
        }
    return p;
}

TEST(Bsdf, SamplingMatchesPdfChiSquare) {
    const std::vector<Config> cs = configs();
    const double alpha = ett::sidak_alpha(0.01, static_cast<int>(cs.size()));
    std::mt19937 rng(2024);
    std::uniform_real_distribution<float> U(0.0f, 0.99999994f);
    for (const Config& c : cs) {
        const etk::float3 wo = wo_of(c.cos_o);
        std::ostringstream label;
        label << c.name << " roughness " << c.m.alpha << " cos(theta_o) " << c.cos_o;
        SCOPED_TRACE(label.str());
        std::vector<double> observed(kPhi * (kTheta + 1), 0.0);
        int lost = 0;
        for (int k = 0; k < kSamples; ++k) {
            const etk::float2 u = etk::make_float2(U(rng), U(rng));
            const etk::EtkBsdfSample s = etk::etk_bsdf_sample(c.m, wo, u, U(rng));
            if (!(s.pdf > 0.0f)) {
                ++lost;
                continue;
            }
            ASSERT_GT(s.wi.z, 0.0f);
            ASSERT_NEAR(std::sqrt(etk::dot(s.wi, s.wi)), 1.0f, 1e-5f);
            // The density and weight handed out with the sample are the pdf and f cos / pdf.
            const float pdf = etk::etk_bsdf_pdf(c.m, wo, s.wi);
            ASSERT_NEAR(s.pdf, pdf, 1e-5f * pdf);
            const float w = etk::etk_bsdf_eval(c.m, wo, s.wi).x * s.wi.z / pdf;
            ASSERT_NEAR(s.weight.x, w, 1e-5f * w + 1e-7f);
            observed[bin_of(s.wi)] += 1.0;
        }
        observed[kPhi * kTheta] = lost;
        const std::vector<double> prob = integrate_pdf(c.m, wo);
        std::vector<double> expected(kPhi * (kTheta + 1), 0.0);
        double total = 0.0;
        for (int i = 0; i < kPhi * kTheta; ++i) {
            expected[i] = prob[i] * kSamples;
            total += prob[i];
        }
        expected[kPhi * kTheta] = std::max(0.0, 1.0 - total) * kSamples;

        // The pdf integrates to at most one, and what it misses is what sampling loses below
        // the horizon (binomial noise, 5 sigma, plus 1e-4 of quadrature error).
        const double lost_fraction = double(lost) / kSamples;
        EXPECT_LE(total, 1.0 + 1e-4);
        EXPECT_NEAR(1.0 - total, lost_fraction,
                    5 * std::sqrt(std::max(lost_fraction, 1e-6) / kSamples) + 1e-4)
            << "pdf integral " << total << ", lost " << lost_fraction;
        if (c.m.type == ETK_MAT_DIFFUSE) {
            EXPECT_EQ(lost, 0);
            EXPECT_NEAR(total, 1.0, 1e-4);
        }

        const ett::Chi2Result r = ett::chi2_test(observed, expected, kPhi, kTheta + 1, alpha);
        if (!r.passed)
            ett::dump_histograms("bsdf-chi2-" + std::string(c.name), observed, expected, kPhi,
                                 kTheta + 1);
        EXPECT_TRUE(r.passed) << r.report;
        std::printf("%-40s pdf integral %.5f, lost %.5f, chi2 p = %.3g (dof %d)\n",
                    label.str().c_str(), total, lost_fraction, r.p_value, r.dof);
    }
}

TEST(Bsdf, EvaluationIsReciprocal) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    auto dir = [&] {
        const float z = std::max(1e-3f, U(rng)), s = std::sqrt(1 - z * z),
                    ph = 2 * float(M_PI) * U(rng);
        return etk::make_float3(s * std::cos(ph), s * std::sin(ph), z);
    };
    for (const Config& c : configs())
        for (int k = 0; k < 20000; ++k) {
            const etk::float3 a = dir(), b = dir();
            const etk::float3 fab = etk::etk_bsdf_eval(c.m, a, b),
                              fba = etk::etk_bsdf_eval(c.m, b, a);
            for (float x : {fab.x, fab.y, fab.z})
                ASSERT_TRUE(std::isfinite(x) && x >= 0.0f) << c.name;
            // f(a, b) and f(b, a) differ only by rounding: of dot(wi, h) vs dot(wo, h) in the
            // Fresnel term, where h = normalize(a + b) carries a relative error ~eps / |a + b|
            // (cancellation when a and b are nearly opposite grazing directions).
            const float cond = 1.0f + 1.0f / etk::length(a + b);
            ASSERT_NEAR(fab.x, fba.x, 1e-5f * cond * std::max(fab.x, fba.x) + 1e-9f)
                << c.name << " roughness " << c.m.alpha << " wo.z " << a.z << " wi.z " << b.z;
        }
}

// A white base (albedo 1) under the GGX lobe reflects exactly what it receives, at every angle
// and roughness: the directional albedo, estimated as the mean of the sampler's f cos / pdf
// (bounded with visible normals), is 1 within its noise and the table's interpolation
// (kernels/base_albedo_table.h, ~0.004). A base weighted by a constant 1 - F0 reflected 1.61 at
// 85 degrees (F0 0.04, smooth); one coupled by Schlick's 1 - F(cos) in place of the lobe's
// albedo, 0.29 at 88 degrees under alpha 0.3 (the lobe's shadowing reflects less than F).
TEST(Bsdf, WhiteBaseUnderTheLobeReflectsWhatItReceives) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    for (float f0 : {0.04f, 0.5f})
        for (float alpha : {0.01f, 0.1f, 0.3f, 1.0f})
            for (float cos_o : {1.0f, 0.5f, 0.17f, 0.087f, 0.03f}) {
                const etk::EtkMaterial m = material(ETK_MAT_MICROFACET, 1.0f, f0, alpha, 1);
                const etk::float3 wo =
                    etk::make_float3(std::sqrt(1.0f - cos_o * cos_o), 0.0f, cos_o);
                const int n = 1 << 17;
                double sum = 0.0, sum2 = 0.0;
                for (int k = 0; k < n; ++k) {
                    const etk::EtkBsdfSample s =
                        etk::etk_bsdf_sample(m, wo, etk::make_float2(U(rng), U(rng)), U(rng));
                    const double w = s.pdf > 0.0f ? s.weight.x : 0.0;
                    sum += w;
                    sum2 += w * w;
                }
                const double mean = sum / n, sigma = std::sqrt((sum2 / n - mean * mean) / n);
                EXPECT_NEAR(mean, 1.0, 4.0 * sigma + 0.006)
                    << "F0 " << f0 << " alpha " << alpha << " cos_o " << cos_o << ": +- " << sigma;
            }
}

TEST(Bsdf, NothingBelowTheHorizonOrFromBehind) {
    const etk::EtkMaterial m = material(ETK_MAT_MICROFACET, 0.5f, 0.04f, 0.3f);
    const etk::float3 up = etk::make_float3(0, 0, 1), down = etk::make_float3(0.6f, 0, -0.8f);
    EXPECT_EQ(etk::etk_bsdf_eval(m, up, down).x, 0.0f);
    EXPECT_EQ(etk::etk_bsdf_eval(m, down, up).x, 0.0f);
    EXPECT_EQ(etk::etk_bsdf_pdf(m, up, down), 0.0f);
    EXPECT_EQ(etk::etk_bsdf_sample(m, down, etk::make_float2(0.3f, 0.7f), 0.1f).pdf, 0.0f);
}

// etk_bsdf_pdf_bound (the compensated strategy's last BSDF sample share, integrator.h): at every
// wo it bounds etk_bsdf_pdf over all wi -- random wi and the lobe's own samples, where the density
// peaks -- and head-on (alpha < 1) the bound is the density at wi = n, so it is not loose there;
// NDF-sampled lobes, glass and mirrors have none, and nothing reflects from below.
TEST(Bsdf, PdfBoundHoldsEverywhereAndIsReachedHeadOn) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<etk::EtkMaterial> ms = {material(ETK_MAT_DIFFUSE, 0.8f, 0.0f, 0.3f)};
    for (float alpha : {0.001f, 0.05f, 0.2f, 0.5f, 1.0f, 1.6f}) {
        ms.push_back(material(ETK_MAT_MICROFACET, 0.0f, 0.9f, alpha, 1));
        ms.push_back(material(ETK_MAT_MICROFACET, 0.5f, 0.04f, alpha, 1));
        ms.push_back(conductor(alpha, 1));
    }
    const etk::float3 n = etk::make_float3(0, 0, 1);
    for (const etk::EtkMaterial& m : ms)
        for (float cos_o : {1.0f, 0.7f, 0.3f, 0.05f, 1e-4f}) {
            const etk::float3 wo = etk::make_float3(std::sqrt(1.0f - cos_o * cos_o), 0.0f, cos_o);
            const float bound = etk::etk_bsdf_pdf_bound(m, wo);
            ASSERT_TRUE(std::isfinite(bound) && bound > 0.0f);
            float most = 0.0f;
            for (int i = 0; i < 20000; ++i) {
                const etk::float2 u = etk::make_float2(U(rng), U(rng));
                etk::float3 wi = etk::etk_sample_uniform_sphere(u);
                if (i % 2) // the lobe's own directions
                    wi = etk::etk_bsdf_sample(m, wo, u, U(rng)).wi;
                most = std::max(most, etk::etk_bsdf_pdf(m, wo, wi));
            }
            EXPECT_LE(most, bound * 1.0001f)
                << "type " << m.type << " alpha " << m.alpha << " wo.z " << cos_o;
            // (Not at alpha 0.001, where D(n)'s float cancellation, 1 + (a^2 - 1), is ~6%.)
            if (cos_o == 1.0f && m.alpha >= 0.05f && m.alpha < 1.0f) {
                EXPECT_NEAR(etk::etk_bsdf_pdf(m, wo, n), bound, 1e-4f * bound)
                    << "type " << m.type << " alpha " << m.alpha;
            }
        }
    const etk::float3 up = n, below = etk::make_float3(0.6f, 0.0f, -0.8f);
    EXPECT_EQ(etk::etk_bsdf_pdf_bound(material(ETK_MAT_MICROFACET, 0.5f, 0.04f, 0.2f, 0), up),
              ETK_PDF_UNBOUNDED);
    EXPECT_EQ(etk::etk_bsdf_pdf_bound(material(ETK_MAT_MIRROR, 0.0f, 0.9f, 0.2f), up),
              ETK_PDF_UNBOUNDED);
    EXPECT_EQ(etk::etk_bsdf_pdf_bound(material(ETK_MAT_DIELECTRIC, 1.0f, 0.0f, 0.2f), up),
              ETK_PDF_UNBOUNDED);
    EXPECT_EQ(etk::etk_bsdf_pdf_bound(material(ETK_MAT_DIFFUSE, 0.8f, 0.0f, 0.3f), below), 0.0f);
    // A lobe of F0 0 under a white base: the diffuse bound even where NDF sampling has none.
    EXPECT_FLOAT_EQ(etk::etk_bsdf_pdf_bound(material(ETK_MAT_MICROFACET, 1.0f, 0.0f, 0.2f, 0), up),
                    1.0f / float(M_PI));
}

// The conductor's Fresnel reflectance: a dielectric's when k = 0 (at every angle, against
// dielectric.h's own formula), the closed form ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2) head-on, 1 at
// grazing incidence, and between 0 and 1 growing towards grazing for metals.
TEST(Bsdf, ConductorFresnelIsTheDielectricsAtZeroKAndTheClosedFormHeadOn) {
    for (float eta : {1.1f, 1.33f, 1.5f, 2.4f, 3.5f})
        for (int i = 0; i <= 100; ++i) {
            const float c = std::max(1e-4f, i / 100.0f);
            EXPECT_NEAR(etk::etk_fresnel_conductor1(eta, 0.0f, c),
                        etk::etk_fresnel_dielectric(c, eta), 2e-6f)
                << "eta " << eta << " cos " << c;
        }
    const float metals[][2] = {{0.143f, 3.983f}, {0.201f, 3.913f}, {1.658f, 9.224f},
                               {4.370f, 5.207f}, {1.0f, 0.5f},     {0.05f, 0.05f}};
    for (const auto& nk : metals) {
        const float n = nk[0], k = nk[1];
        EXPECT_NEAR(etk::etk_fresnel_conductor1(n, k, 1.0f),
                    ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k), 1e-6f);
        EXPECT_NEAR(etk::etk_fresnel_conductor1(n, k, 0.0f), 1.0f, 1e-6f);
        for (int i = 0; i <= 100; ++i) {
            const float f = etk::etk_fresnel_conductor1(n, k, i / 100.0f);
            ASSERT_TRUE(f >= 0.0f && f <= 1.0f) << n << " " << k << " " << i;
        }
    }
    // Near eta = 1, k = 0 (a channel a user sets to "no metal") the reflectance is rounding
    // only: never below zero, or the pixels it lights go negative.
    for (float n : {0.999f, 1.0f, 1.001f})
        for (float k : {0.0f, 1e-4f, 1e-3f})
            for (int i = 0; i <= 10000; ++i) {
                const float f = etk::etk_fresnel_conductor1(n, k, i / 10000.0f);
                ASSERT_TRUE(f >= 0.0f && f <= 1.0f) << n << " " << k << " " << i << ": " << f;
            }
}

// A conductor whose reflectance is 1 everywhere (k -> infinity) is the Cook-Torrance lobe of
// F0 = 1 with no base: the same GGX, Smith and sampling, only the Fresnel factor differs.
TEST(Bsdf, ConductorOfUnitReflectanceIsTheMicrofacetLobeOfUnitF0) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> U(0.0f, 0.99999994f);
    for (float alpha : {0.05f, 0.3f, 1.0f})
        for (int vndf : {ETK_GGX_NDF, ETK_GGX_VNDF}) {
            etk::EtkMaterial metal = material(ETK_MAT_CONDUCTOR, 0.0f, 0.0f, alpha, vndf);
            metal.albedo = etk::make_float3(1.0f, 1.0f, 1.0f);
            metal.specular = etk::make_float3(1e4f, 1e4f, 1e4f);
            const etk::EtkMaterial ct = material(ETK_MAT_MICROFACET, 0.0f, 1.0f, alpha, vndf);
            for (int k = 0; k < 2000; ++k) {
                const etk::float3 wo = wo_of(std::max(0.02f, U(rng)));
                const etk::float2 u = etk::make_float2(U(rng), U(rng));
                const float lobe = U(rng);
                const etk::EtkBsdfSample a = etk::etk_bsdf_sample(metal, wo, u, lobe),
                                         b = etk::etk_bsdf_sample(ct, wo, u, lobe);
                ASSERT_EQ(a.pdf, b.pdf);
                ASSERT_NEAR(a.weight.x, b.weight.x, 1e-3f * b.weight.x + 1e-7f);
                if (b.pdf > 0.0f) {
                    const float f = etk::etk_bsdf_eval(ct, wo, b.wi).y;
                    ASSERT_NEAR(etk::etk_bsdf_eval(metal, wo, b.wi).y, f, 1e-3f * f);
                }
            }
        }
}

// A metal's value is its Fresnel reflectance at wi . h times the lobe of unit reflectance: the
// conductor's Fresnel is the one evaluated (gold, per channel), nothing else of the lobe changes.
TEST(Bsdf, ConductorIsItsFresnelTimesTheLobeOfUnitReflectance) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> U(0.0f, 0.99999994f);
    for (float alpha : {0.05f, 0.3f}) {
        const etk::EtkMaterial gold = conductor(alpha, 1),
                               unit = material(ETK_MAT_MICROFACET, 0.0f, 1.0f, alpha, 1);
        for (int k = 0; k < 2000; ++k) {
            const etk::float3 wo = wo_of(std::max(0.02f, U(rng)));
            const etk::EtkBsdfSample s =
                etk::etk_bsdf_sample(unit, wo, etk::make_float2(U(rng), U(rng)), U(rng));
            if (!(s.pdf > 0.0f))
                continue;
            const etk::float3 h = etk::normalize(wo + s.wi);
            const etk::float3 f = etk::etk_fresnel_conductor(gold.albedo, gold.specular,
                                                             etk::dot(s.wi, h)),
                              one = etk::etk_bsdf_eval(unit, wo, s.wi),
                              g = etk::etk_bsdf_eval(gold, wo, s.wi);
            ASSERT_NEAR(g.x, f.x * one.x, 1e-5f * f.x * one.x);
            ASSERT_NEAR(g.z, f.z * one.z, 1e-5f * f.z * one.z);
            ASSERT_EQ(etk::etk_bsdf_pdf(gold, wo, s.wi), etk::etk_bsdf_pdf(unit, wo, s.wi));
        }
    }
}

} // namespace
