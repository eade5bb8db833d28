#include "render/light_share.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace et {
namespace {

double luma(const float4& v) {
    return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z;
}

} // namespace

LightShareLearner::LightShareLearner(const LightShareOptions& options, int width, int height,
                                     uint32_t seed)
    : opt_(options), width_(width), height_(height), seed_(seed) {}

void LightShareLearner::begin_pass() {
    bins_.emplace_back(static_cast<size_t>(width_) * height_, -1);
}

void LightShareLearner::end_pass(const std::vector<float4>& pass) {
    std::vector<float> v(pass.size());
    for (size_t i = 0; i < v.size(); ++i) {
        const double x = luma(pass[i]);
        v[i] = std::isfinite(x) ? static_cast<float>(x) : 0.0f;
        image_sum_ += v[i];
        image_count_ += pass[i].w;
    }
    values_.push_back(std::move(v));
}

std::array<std::array<LightShareLearner::Cell, ETK_SHARE_CANDIDATES>, ETK_SHARE_BINS>
LightShareLearner::measure() const {
    std::array<std::array<Cell, ETK_SHARE_CANDIDATES>, ETK_SHARE_BINS> cells{};
    if (values_.size() < 2)
        return cells;
    // Relative weights 1 / (m^2 + eps): m the pixel's mean luminance over the other learning
    // passes, eps = (2% of the image's mean)^2 so that black pixels do not dominate.
    const double mean = image_count_ > 0.0 ? image_sum_ / image_count_ : 0.0;
    const double eps = std::max(1e-30, (0.02 * mean) * (0.02 * mean));
    struct Pair {
        int bin, k;
        double v;
    };
    std::vector<Pair> pairs;
    std::array<std::vector<double>, ETK_SHARE_BINS> by_bin;
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            const size_t px = static_cast<size_t>(y) * width_ + x;
            const int k = etk::etk_learning_candidate(seed_, static_cast<int>(px));
            double all_values = 0.0;
            for (const auto& v : values_)
                all_values += v[px];
            // Pairs of blocks of B consecutive passes: passes [2jB, 2jB+B) against
            // [2jB+B, 2jB+2B). Each block is a B-sample QMC estimate (the sampler's first 2^m
            // samples form nets), so the difference measures the error the image will have,
            // stratification included -- which per-sample variance does not see.
            const size_t B = static_cast<size_t>(std::max(1, opt_.block));
            for (size_t p = 0; p + 2 * B <= values_.size(); p += 2 * B) {
                const int bin = bins_[p][px];
                bool same = bin >= 0 && bin < ETK_SHARE_BINS;
                double a = 0.0, c = 0.0;
                for (size_t q = 0; q < B && same; ++q) {
                    same = bins_[p + q][px] == bin && bins_[p + B + q][px] == bin;
                    a += values_[p + q][px];
                    c += values_[p + B + q][px];
                }
                if (!same)
                    continue; // no non-delta first hit, or not the same material throughout
                const double d = (a - c) / double(B);
                // The pixel's mean from the other passes: independent of this pair's values,
                // so a pair's own outlier does not lower its weight.
                const double m = values_.size() > 2 * B
                                     ? (all_values - a - c) / double(values_.size() - 2 * B)
                                     : (a + c) / double(2 * B);
                const double w = 1.0 / (m * m + eps);
                pairs.push_back({bin, k, w * 0.5 * d * d});
                by_bin[bin].push_back(pairs.back().v);
            }
        }
    // Heavy tails: a few fireflies among a few pairs decide a plain mean by chance. Each value
    // is capped at kCap x the median of its bin (all candidates together), so that the choice
    // follows the bulk of the distribution; the cap only steers the choice -- every candidate
    // is an unbiased estimator.
    constexpr double kCap = 50.0;
    std::array<double, ETK_SHARE_BINS> cap;
    for (int b = 0; b < ETK_SHARE_BINS; ++b) {
        auto& v = by_bin[b];
        cap[b] = std::numeric_limits<double>::infinity();
        if (v.empty())
            continue;
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        if (v[v.size() / 2] > 0.0)
            cap[b] = kCap * v[v.size() / 2];
    }
    for (const Pair& q : pairs) {
        cells[q.bin][q.k].sum += std::min(q.v, cap[q.bin]);
        ++cells[q.bin][q.k].pixels;
    }
    return cells;
}

std::array<int, ETK_SHARE_BINS> LightShareLearner::choices() const {
    const auto cells = measure();
    std::array<int, ETK_SHARE_BINS> out;
    out.fill(kDefaultCandidate);
    for (int b = 0; b < ETK_SHARE_BINS; ++b) {
        bool enough = true;
        for (const Cell& c : cells[b])
            enough = enough && c.pixels >= static_cast<uint64_t>(opt_.min_pixels);
        if (!enough)
            continue;
        double best = 0.0;
        for (int k = 0; k < ETK_SHARE_CANDIDATES; ++k) {
            const double v = cells[b][k].sum / double(cells[b][k].pixels);
            if (k == 0 || v < best) {
                best = v;
                out[b] = k;
            }
        }
    }
    return out;
}

} // namespace et
