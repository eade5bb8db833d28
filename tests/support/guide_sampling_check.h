// The check every table-guided light sampler passes (kernels/visibility_guide.h etk_guide_sample:
// the visibility strategy's cells, the cosine strategy's bins): n samples of one cell's table
// against the density it reports, which must be the density evaluated for MIS at the same
// direction, bit for bit; chi-square over the map's distribution cells, where both are piecewise
// constant in the lat-long square so the expected counts are exact; the density's integral; and
// E[1 / pdf], the sphere's area where every direction has a density.
#pragma once
#include "chi2.h"
#include "kernels/visibility_guide.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace ett {

struct GuideSamplingCheck {
    int bad = 0;        // samples with no finite positive density
    int mismatched = 0; // samples whose density differs from etk_guide_factor's evaluation
    double integral = 0.0;
    Chi2Result chi;
    double mean_inv_pdf = 0.0, sd_inv_pdf = 0.0; // E[1 / pdf] and its standard error
};

inline GuideSamplingCheck check_guide_sampling(const etk::EtkScene& S, const etk::EtkParams& p,
                                               int cell, int n, uint32_t seed, double alpha) {
    const int w = p.env.dist_w, h = p.env.dist_h;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<double> observed(static_cast<size_t>(w) * h, 0.0);
    GuideSamplingCheck r;
    double inv_pdf = 0.0, inv_pdf2 = 0.0;
    for (int i = 0; i < n; ++i) {
        const etk::float2 u =
            etk::make_float2(std::min(U(rng), 0.99999994f), std::min(U(rng), 0.99999994f));
        const etk::EtkEnvSample s = etk::etk_guide_sample(S, p, cell, u);
        if (!(s.pdf > 0.0f) || !std::isfinite(s.pdf)) {
            ++r.bad;
            continue;
        }
        observed[static_cast<size_t>(etk::etk_cell_of(s.uv.y, h)) * w +
                 etk::etk_cell_of(s.uv.x, w)] += 1.0;
        r.mismatched += etk::etk_env_pdf_uv(S.env_dist, p.env, s.uv) *
                            etk::etk_guide_factor(S, p, cell, s.uv) !=
                        s.pdf;
        inv_pdf += 1.0 / s.pdf;
        inv_pdf2 += 1.0 / (double(s.pdf) * s.pdf);
    }
    std::vector<double> expected(observed.size());
    for (int row = 0; row < h; ++row)
        for (int col = 0; col < w; ++col) {
            const etk::float2 uv = etk::make_float2((col + 0.5f) / w, (row + 0.5f) / h);
            // The map's density as the kernels sample it: from its CDFs' widths (the stored
            // densities differ where a width is held at its least share, env_distribution.cpp).
            const double pmap = etk::etk_pdf_2d(S.env_dist, w, h, uv);
            const double d = pmap * etk::etk_guide_factor(S, p, cell, uv) / (double(w) * h);
            r.integral += d;
            expected[static_cast<size_t>(row) * w + col] = n * d;
        }
    r.chi = chi2_test(observed, expected, w, h, alpha);
    r.mean_inv_pdf = inv_pdf / n;
    r.sd_inv_pdf = std::sqrt(std::max(0.0, inv_pdf2 / n - r.mean_inv_pdf * r.mean_inv_pdf) / n);
    return r;
}

} // namespace ett
