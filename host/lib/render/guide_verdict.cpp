#include "render/guide_verdict.h"

#include "kernels/color.h"
#include "util/error.h"

#include <algorithm>
#include <cmath>

namespace et {

namespace {
constexpr size_t kRadius = 2; // the reference mean's neighbourhood: 5 x 5 pixels
// Every pixel's value counts up to the pooled values' 99.9% quantile: a few fireflies (the sun's
// glint on a metal sphere caught by one block: one pixel of 23,040 held 40% of a technique's error
// on the efficiency suite's esplanade scene) must not decide, while the errors MIS makes in a room
// lit through an opening, spread over many pixels, change by 2-3% (window_room, skylight_room,
// bunny_grace).
constexpr double kTrim = 0.999;
// The kept technique must win by this many standard errors of the ratio's log (one-sided, about
// 84%): the errors are means over the measured pixels, and where a few pixels hold most of the
// difference (a glass statue's shadow under a low sun) the ratio moved between 0.57 and 1.40 from
// seed to seed around a true 0.86 (standard error 0.3-0.56), which took the dearer technique 3
// times in 8; where the difference is spread (standard error 0.06-0.10) it moves the threshold by
// 6-10%.
constexpr double kConfidence = 1.0;
} // namespace

GuideVerdict::GuideVerdict(int width, int height, int passes, double cost)
    : pixels_(static_cast<size_t>(width) * static_cast<size_t>(height)), width_(width),
      passes_(passes), cost_(cost) {
    if (width < 1 || height < 1)
        throw Error("visibility verdict: an empty film");
    if (passes < 4 || passes % 2 != 0)
        throw Error("visibility verdict: needs an even number of passes, at least 4 (got " +
                    std::to_string(passes) + ")");
    for (int k = 0; k < 4; ++k) {
        sum_[k].assign(pixels_, 0.0);
        n_[k].assign(pixels_, 0u);
    }
}

void GuideVerdict::add(int t, int k, const float* film_sum_rgba) {
    if (t < 0 || t > 1 || k != added_[t] || k >= passes_)
        throw Error("visibility verdict: pass " + std::to_string(k) + " of technique " +
                    std::to_string(t) + " out of order");
    const int slot = 2 * t + (k < passes_ / 2 ? 0 : 1);
    std::vector<double>& sum = sum_[slot];
    std::vector<uint32_t>& n = n_[slot];
    for (size_t i = 0; i < pixels_; ++i) {
        const float* s = film_sum_rgba + 4 * i;
        if (!(s[3] > 0.0f))
            continue; // a dropped (non-finite) sample
        sum[i] += etk::etk_luma(etk::make_float3(s[0], s[1], s[2]));
        n[i] += 1u;
    }
    if (++added_[t] == passes_ && added_[1 - t] == passes_)
        decide();
}

void GuideVerdict::decide() {
    // Each pixel's mean over every block, then over its neighbourhood (kRadius pixels each way,
    // clamped at the film's edges; only the pixels every block has samples of, so with the
    // fallback on every 8th pixel the measured ones among them): the reference each block's error
    // is relative to. Not the
    // pixel's own mean -- a block that caught a rare bright sample would then be measured
    // against a mean made of that sample, and heavy tails (the errors MIS makes where the map's
    // light comes through a small opening) would look small (the relative error is then at most
    // ~8 whatever the sample).
    const size_t w = static_cast<size_t>(width_), h = pixels_ / w;
    std::vector<double> pixel_mean(pixels_, 0.0);
    std::vector<uint8_t> full(pixels_, 0);
    for (size_t i = 0; i < pixels_; ++i) {
        if (!(n_[0][i] && n_[1][i] && n_[2][i] && n_[3][i]))
            continue; // a block without a sample here (every one dropped)
        full[i] = 1;
        pixel_mean[i] = (sum_[0][i] + sum_[1][i] + sum_[2][i] + sum_[3][i]) /
                        static_cast<double>(n_[0][i] + n_[1][i] + n_[2][i] + n_[3][i]);
    }
    std::vector<double> ref(pixels_, 0.0);
    double mean = 0.0;
    size_t used = 0;
    for (size_t y = 0; y < h; ++y)
        for (size_t x = 0; x < w; ++x) {
            if (!full[y * w + x])
                continue;
            double s = 0.0;
            int n = 0;
            for (size_t yy = y > kRadius ? y - kRadius : 0; yy <= std::min(h - 1, y + kRadius);
                 ++yy)
                for (size_t xx = x > kRadius ? x - kRadius : 0; xx <= std::min(w - 1, x + kRadius);
                     ++xx)
                    if (full[yy * w + xx]) {
                        s += pixel_mean[yy * w + xx];
                        ++n;
                    }
            ref[y * w + x] = s / n;
            mean += pixel_mean[y * w + x];
            ++used;
        }
    if (used == 0)
        return; // nothing to compare: both errors 0, the fallback (the cheaper)
    mean /= static_cast<double>(used);
    const double floor2 = (0.01 * mean) * (0.01 * mean);
    // Per technique and pixel, half the squared difference of its blocks, relative to the
    // reference; each capped at the pooled values' kTrim quantile.
    std::vector<double> rel[2];
    for (int t = 0; t < 2; ++t) {
        rel[t].reserve(used);
        for (size_t i = 0; i < pixels_; ++i) {
            if (!full[i])
                continue;
            const double d = sum_[2 * t][i] / n_[2 * t][i] - sum_[2 * t + 1][i] / n_[2 * t + 1][i];
            const double denom = ref[i] * ref[i] + floor2;
            rel[t].push_back(denom > 0.0 ? 0.5 * d * d / denom : 0.0);
        }
    }
    std::vector<double> pooled(rel[0]);
    pooled.insert(pooled.end(), rel[1].begin(), rel[1].end());
    const size_t q = std::min(pooled.size() - 1, static_cast<size_t>(kTrim * pooled.size()));
    std::nth_element(pooled.begin(), pooled.begin() + static_cast<std::ptrdiff_t>(q), pooled.end());
    const double cap = pooled[q];
    for (int t = 0; t < 2; ++t) {
        double s = 0.0;
        for (double v : rel[t])
            s += std::min(v, cap);
        error_[t] = s / static_cast<double>(used);
    }
    // The ratio's spread: R = A / B of the two means over the same pixels has, to first order,
    // var(R) / R^2 = var(a - R b) / (n A^2).
    if (error_[0] > 0.0 && error_[1] > 0.0 && std::isfinite(error_[0]) &&
        std::isfinite(error_[1])) {
        const double r = error_[0] / error_[1];
        double s2 = 0.0;
        for (size_t i = 0; i < used; ++i) {
            const double d = std::min(rel[0][i], cap) - r * std::min(rel[1][i], cap);
            s2 += d * d;
        }
        log_ratio_se_ =
            std::sqrt(s2 / static_cast<double>(used) / static_cast<double>(used)) / error_[0];
    }
    decided_ = true;
}

bool GuideVerdict::kept_wins() const {
    return decided_ && error_[0] > 0.0 &&
           error_[0] >= cost_ * error_[1] * std::exp(kConfidence * log_ratio_se_);
}

} // namespace et
