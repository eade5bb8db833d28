#include "prepare/env_compensation.h"

#include "kernels/piecewise_constant.h"
#include "kernels/trig.h"

#include <cmath>
#include <vector>

namespace et {
namespace {
// Relative size of the float rounding in a table's densities (a few ulps of 2^-24).
constexpr double kRoundingTolerance = 1e-5;
} // namespace

EnvDistribution compensate_distribution(const EnvDistribution& full) {
    const int w = full.width, h = full.height;
    if (!full.has_light() || w < 1 || h < 1)
        return full;
    const float* table = full.table.data();
    const float* cond = table + etk::etk_dist2d_conditional_pdf(h);
    // Joint densities p(u, v) = p(v) p(u | v) over the unit square average 1, and are f sin(theta)
    // up to one constant, so the solid-angle mean of f is (sum of p) / (sum of sin theta) =
    // h / sum over rows of sin(theta).
    std::vector<double> sin_row(static_cast<size_t>(h));
    double sin_sum = 0.0;
    for (int r = 0; r < h; ++r) {
        sin_row[r] = std::sin(M_PI * (r + 0.5) / h);
        sin_sum += sin_row[r];
    }
    const double mean_f = h / sin_sum;

    EnvDistribution c;
    c.width = w;
    c.height = h;
    c.table.assign(full.table.size(), 0.0f);
    std::vector<float> g(static_cast<size_t>(w)), row_mass(static_cast<size_t>(h));
    double total = 0.0;
    for (int r = 0; r < h; ++r) {
        const double floor_r = mean_f * sin_row[r];
        for (int col = 0; col < w; ++col) {
            const double joint = double(table[r]) * cond[static_cast<size_t>(r) * w + col];
            // Excess within float rounding of the table (a constant map's cells differ from
            // their mean by an ulp or two) is no excess.
            const double excess = joint - floor_r;
            g[col] = excess > kRoundingTolerance * floor_r ? static_cast<float>(excess) : 0.0f;
        }
        float* pdf =
            c.table.data() + etk::etk_dist2d_conditional_pdf(h) + static_cast<size_t>(r) * w;
        float* cdf = c.table.data() + etk::etk_dist2d_conditional_cdf(w, h) +
                     static_cast<size_t>(r) * (w + 1);
        const double mass = build_piecewise_constant_1d(g.data(), w, pdf, cdf);
        build_cdf_guide(cdf, w,
                        c.table.data() + etk::etk_dist2d_conditional_guide(w, h) +
                            static_cast<size_t>(r) * (etk::etk_guide_cells(w) + 1));
        row_mass[r] = static_cast<float>(mass);
        total += mass;
    }
    if (!(total > 0.0))
        return full; // nothing above the mean: keep the full distribution (see the header)
    c.total = build_piecewise_constant_1d(row_mass.data(), h, c.table.data(),
                                          c.table.data() + etk::etk_dist2d_marginal_cdf(h));
    build_cdf_guide(c.table.data() + etk::etk_dist2d_marginal_cdf(h), h,
                    c.table.data() + etk::etk_dist2d_marginal_guide(w, h));
    return c;
}

} // namespace et
