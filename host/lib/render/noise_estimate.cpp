#include "render/noise_estimate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace et {

double relative_error(const FilmSums& sums) {
    const size_t n = sums.pixels();
    if (n == 0)
        return 0.0;
    for (size_t i = 0; i < n; ++i)
        if (sums.data()[i].count < 2)
            return std::numeric_limits<double>::infinity();
    const std::vector<float> mean = sums.mean(), var = sums.variance_of_mean();
    double level = 0.0; // mean over pixels of |m|^2
    for (size_t i = 0; i < 3 * n; ++i)
        level += double(mean[i]) * mean[i];
    level /= static_cast<double>(n);
    const double eps2 = 1e-4 * level;
    double acc = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double v = 0.0, m2 = 0.0;
        for (int c = 0; c < 3; ++c) {
            v += var[3 * i + c];
            m2 += double(mean[3 * i + c]) * mean[3 * i + c];
        }
        if (v > 0.0)
            acc += v / (m2 + eps2);
    }
    return std::sqrt(acc / static_cast<double>(n));
}

int64_t next_noise_check(int64_t spp, double error, double target) {
    if (!(error < std::numeric_limits<double>::infinity()) || !(target > 0.0))
        return std::max<int64_t>(2 * spp, kNoiseFirstCheck);
    const double want = std::ceil(static_cast<double>(spp) * (error / target) * (error / target));
    return std::clamp<int64_t>(static_cast<int64_t>(std::min(want, 1e15)), spp + 1, 2 * spp);
}

} // namespace et
