#include "chi2.h"

#include "image/image_io.h"
#include "test_data.h"

#include <boost/math/distributions/chi_squared.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace ett {

double sidak_alpha(double alpha, int tests) {
    return 1.0 - std::pow(1.0 - alpha, 1.0 / tests);
}

Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                     int width, int height, double alpha, double min_expected,
                     double zero_cell_slack) {
    Chi2Result r;
    r.alpha = alpha;
    const size_t n = expected.size();
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return expected[a] < expected[b]; });

    double pool_obs = 0.0, pool_exp = 0.0;
    int cells = 0;
    for (size_t k = 0; k < n; ++k) {
        const size_t i = order[k];
        if (expected[i] <= 0.0) {
            r.samples_in_zero_cells += observed[i];
            continue;
        }
        if (expected[i] < min_expected) {
            pool_obs += observed[i];
            pool_exp += expected[i];
            ++r.pooled_cells;
            if (pool_exp >= min_expected) {
                r.statistic += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
                ++cells;
                pool_obs = pool_exp = 0.0;
            }
        } else {
            r.statistic += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
            ++cells;
        }
    }
    if (pool_exp > 0.0) {
        r.statistic += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        ++cells;
    }
    r.dof = cells - 1;
    if (r.dof > 0) {
        boost::math::chi_squared dist(r.dof);
        r.p_value = boost::math::cdf(boost::math::complement(dist, r.statistic));
    } else {
        r.p_value = 1.0; // one cell after pooling: nothing to test beyond the zero cells
    }
    r.passed = r.samples_in_zero_cells <= zero_cell_slack && r.p_value >= alpha;

    std::ostringstream os;
    os << "chi2 = " << r.statistic << ", dof = " << r.dof << ", p = " << r.p_value << " (alpha "
       << alpha << "), " << r.pooled_cells << " cells pooled, " << r.samples_in_zero_cells
       << " samples in zero-expected cells (allowed " << zero_cell_slack
       << ")\nworst cells (phi bin, "
       << "cos-theta bin: observed / expected):";
    std::vector<size_t> worst(n);
    std::iota(worst.begin(), worst.end(), size_t(0));
    auto score = [&](size_t i) {
        double d = observed[i] - expected[i];
        return expected[i] > 0.0 ? d * d / expected[i] : (observed[i] > 0 ? 1e300 : 0.0);
    };
    const size_t shown = std::min<size_t>(10, n);
    std::partial_sort(worst.begin(), worst.begin() + shown, worst.end(),
                      [&](size_t a, size_t b) { return score(a) > score(b); });
    for (size_t k = 0; k < shown; ++k) {
        const size_t i = worst[k];
        os << "\n  (" << i % width << ", " << i / width << "): " << observed[i] << " / "
           << expected[i];
    }
    (void)height;
    r.report = os.str();
    return r;
}

std::string dump_histograms(const std::string& name, const std::vector<double>& observed,
                            const std::vector<double>& expected, int width, int height) {
    try {
        std::vector<float> px(static_cast<size_t>(width) * height * 3);
        for (size_t i = 0; i < observed.size(); ++i) {
            px[3 * i] = static_cast<float>(observed[i]);
            px[3 * i + 1] = static_cast<float>(expected[i]);
            px[3 * i + 2] = static_cast<float>(
                expected[i] > 0 ? (observed[i] - expected[i]) / std::sqrt(expected[i]) : 0.0);
        }
        const std::string path = scratch_dir("chi2-" + name) + "/histograms.exr";
        et::write_image(path, width, height, 3, px);
        return path;
    } catch (const std::exception&) {
        return "";
    }
}

} // namespace ett
