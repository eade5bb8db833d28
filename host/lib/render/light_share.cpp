#include "render/light_share.h"

#include <algorithm>
#include <cmath>

namespace et {
namespace {

constexpr int kTile = 8; // weights from 8x8-pixel tile means: less noise than one pixel

double luma(const float4& v) {
    return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z;
}

} // namespace

LightShareLearner::LightShareLearner(const LightShareOptions& options, int width, int height,
                                     uint32_t seed)
    : opt_(options), width_(width), height_(height), seed_(seed) {}

void LightShareLearner::begin_pass(const std::vector<float4>& film_sum) {
    before_ = film_sum;
    bins_.emplace_back(static_cast<size_t>(width_) * height_, -1);
}

void LightShareLearner::end_pass(const std::vector<float4>& film_sum) {
    std::vector<float> v(film_sum.size());
    for (size_t i = 0; i < v.size(); ++i) {
        // One sample was added: the difference of sums, rounded as the film rounded it.
        const double x = luma(film_sum[i]) - luma(before_[i]);
        v[i] = std::isfinite(x) ? static_cast<float>(x) : 0.0f;
    }
    values_.push_back(std::move(v));
    last_ = film_sum;
}

std::array<std::array<LightShareLearner::Cell, ETK_SHARE_CANDIDATES>, ETK_SHARE_BINS>
LightShareLearner::measure() const {
    std::array<std::array<Cell, ETK_SHARE_CANDIDATES>, ETK_SHARE_BINS> cells{};
    if (last_.empty())
        return cells;
    // Relative weights 1 / (m^2 + eps): m the tile's mean luminance, eps = (2% of the image's
    // mean)^2 so that black tiles do not dominate.
    const int tw = (width_ + kTile - 1) / kTile, th = (height_ + kTile - 1) / kTile;
    std::vector<double> sum(static_cast<size_t>(tw) * th, 0.0), n(sum.size(), 0.0);
    double all = 0.0, all_n = 0.0;
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            const float4& v = last_[static_cast<size_t>(y) * width_ + x];
            const double l = std::isfinite(luma(v)) ? luma(v) : 0.0;
            const size_t t = static_cast<size_t>(y / kTile) * tw + x / kTile;
            sum[t] += l;
            n[t] += v.w;
            all += l;
            all_n += v.w;
        }
    const double mean = all_n > 0.0 ? all / all_n : 0.0;
    const double eps = std::max(1e-30, (0.02 * mean) * (0.02 * mean));
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            const size_t px = static_cast<size_t>(y) * width_ + x;
            const size_t t = static_cast<size_t>(y / kTile) * tw + x / kTile;
            const double m = n[t] > 0.0 ? sum[t] / n[t] : 0.0;
            const double w = 1.0 / (m * m + eps);
            const int k = etk::etk_learning_candidate(seed_, static_cast<int>(px));
            for (size_t p = 0; p + 1 < values_.size(); p += 2) {
                const int bin = bins_[p][px];
                if (bin < 0 || bin >= ETK_SHARE_BINS || bins_[p + 1][px] != bin)
                    continue; // no non-delta first hit, or not the same material twice
                const double d = double(values_[p][px]) - double(values_[p + 1][px]);
                cells[bin][k].sum += w * 0.5 * d * d;
                ++cells[bin][k].pixels;
            }
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
