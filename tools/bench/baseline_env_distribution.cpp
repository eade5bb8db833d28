// The distribution builder exactly as it was before the optimisation (commit 4811176), kept for
// side-by-side benchmarks and for checking that the optimised build gives the same tables.
#include "baseline_env_distribution.h"

#include "kernels/piecewise_constant.h"

#include <algorithm>
#include <cmath>

namespace et::baseline {
namespace {

// The bilinear cell-mean taps [1 6 1]/8 convolved with a truncated, normalised Gaussian.
std::vector<float> filter_taps(float sigma) {
    std::vector<float> g{1.0f};
    if (sigma > 0.0f) {
        int r = std::max(1, static_cast<int>(std::ceil(3.0f * sigma)));
        g.assign(2 * r + 1, 0.0f);
        double sum = 0.0;
        for (int i = -r; i <= r; ++i)
            sum += g[i + r] = std::exp(-0.5f * i * i / (sigma * sigma));
        for (float& x : g)
            x = static_cast<float>(x / sum);
    }
    const float box[3] = {0.125f, 0.75f, 0.125f};
    std::vector<float> taps(g.size() + 2, 0.0f);
    for (size_t i = 0; i < g.size(); ++i)
        for (int j = 0; j < 3; ++j)
            taps[i + j] += g[i] * box[j];
    return taps;
}

// Horizontal pass (wraps around in phi) then vertical pass (clamps at the poles), in place.
void separable_filter(std::vector<float>& img, int w, int h, const std::vector<float>& taps) {
    const int r = static_cast<int>(taps.size() / 2);
    const int k = static_cast<int>(taps.size());
    std::vector<float> pad(w + 2 * r);
    for (int y = 0; y < h; ++y) {
        float* row = &img[static_cast<size_t>(y) * w];
        for (int x = 0; x < w + 2 * r; ++x)
            pad[x] = row[((x - r) % w + w) % w];
        std::fill(row, row + w, 0.0f);
        for (int t = 0; t < k; ++t) {
            const float wt = taps[t];
            const float* src = pad.data() + t;
            for (int x = 0; x < w; ++x)
                row[x] += wt * src[x];
        }
    }
    std::vector<float> col(static_cast<size_t>(w) * h, 0.0f);
    for (int y = 0; y < h; ++y) {
        float* dst = &col[static_cast<size_t>(y) * w];
        for (int t = 0; t < k; ++t) {
            const int sy = std::clamp(y + t - r, 0, h - 1);
            const float wt = taps[t];
            const float* src = &img[static_cast<size_t>(sy) * w];
            for (int x = 0; x < w; ++x)
                dst[x] += wt * src[x];
        }
    }
    img.swap(col);
}

// Area-weighted resampling weights from n input cells to m output cells over the same interval.
struct Span {
    int first;
    std::vector<float> weights;
};
std::vector<Span> area_weights(int n, int m) {
    std::vector<Span> spans(m);
    const double scale = static_cast<double>(n) / m;
    for (int o = 0; o < m; ++o) {
        double a = o * scale, b = (o + 1) * scale;
        int i0 = static_cast<int>(std::floor(a)), i1 = std::min(n, static_cast<int>(std::ceil(b)));
        spans[o].first = i0;
        for (int i = i0; i < i1; ++i)
            spans[o].weights.push_back(
                static_cast<float>((std::min(b, i + 1.0) - std::max(a, double(i))) / scale));
    }
    return spans;
}

std::vector<float> resample(const std::vector<float>& img, int w, int h, int ow, int oh) {
    if (ow == w && oh == h)
        return img;
    auto sx = area_weights(w, ow), sy = area_weights(h, oh);
    std::vector<float> tmp(static_cast<size_t>(ow) * h, 0.0f),
        out(static_cast<size_t>(ow) * oh, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < ow; ++x) {
            float s = 0.0f;
            for (size_t i = 0; i < sx[x].weights.size(); ++i)
                s += sx[x].weights[i] * img[static_cast<size_t>(y) * w + sx[x].first + i];
            tmp[static_cast<size_t>(y) * ow + x] = s;
        }
    for (int y = 0; y < oh; ++y)
        for (size_t i = 0; i < sy[y].weights.size(); ++i) {
            const float wt = sy[y].weights[i];
            const float* src = &tmp[static_cast<size_t>(sy[y].first + i) * ow];
            float* dst = &out[static_cast<size_t>(y) * ow];
            for (int x = 0; x < ow; ++x)
                dst[x] += wt * src[x];
        }
    return out;
}

} // namespace

double build_piecewise_constant_1d(const float* f, int n, float* pdf, float* cdf) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        sum += f[i];
    cdf[0] = 0.0f;
    if (!(sum > 0.0)) {
        // No mass: a linear CDF keeps the binary search well defined; densities stay zero.
        for (int i = 0; i < n; ++i) {
            pdf[i] = 0.0f;
            cdf[i + 1] = static_cast<float>(i + 1) / n;
        }
        cdf[n] = 1.0f;
        return 0.0;
    }
    const double inv = 1.0 / sum;
    const float density_scale = static_cast<float>(n * inv);
    double run = 0.0;
    for (int i = 0; i < n; ++i) {
        pdf[i] = f[i] * density_scale;
        run += f[i];
        cdf[i + 1] = static_cast<float>(run * inv);
    }
    cdf[n] = 1.0f;
    return sum;
}

EnvDistribution build_env_distribution(const RgbImage& image, const DistributionOptions& options) {
    const int w = image.width, h = image.height;
    const int dw = options.width > 0 ? options.width : w;
    const int dh = options.height > 0 ? options.height : h;

    std::vector<float> lum(static_cast<size_t>(w) * h);
    for (size_t p = 0; p < lum.size(); ++p)
        lum[p] = luminance(&image.rgb[3 * p]);
    separable_filter(lum, w, h, filter_taps(options.blur_sigma));
    std::vector<float> f = resample(lum, w, h, dw, dh);

    EnvDistribution d;
    d.width = dw;
    d.height = dh;
    d.table.assign(etk::etk_dist2d_size(dw, dh), 0.0f);
    float* cond_pdf = d.table.data() + etk::etk_dist2d_conditional_pdf(dh);
    float* cond_cdf = d.table.data() + etk::etk_dist2d_conditional_cdf(dw, dh);
    std::vector<float> row_mass(dh);
    for (int y = 0; y < dh; ++y) {
        const float sin_theta = std::sin(static_cast<float>(M_PI) * (y + 0.5f) / dh);
        float* fr = &f[static_cast<size_t>(y) * dw];
        for (int x = 0; x < dw; ++x)
            fr[x] = std::max(0.0f, fr[x]) * sin_theta; // max: filters never go negative, NaN-safe
        row_mass[y] = static_cast<float>(
            build_piecewise_constant_1d(fr, dw, cond_pdf + static_cast<size_t>(y) * dw,
                                        cond_cdf + static_cast<size_t>(y) * (dw + 1)));
    }
    d.total = build_piecewise_constant_1d(row_mass.data(), dh, d.table.data(),
                                          d.table.data() + etk::etk_dist2d_marginal_cdf(dh));
    return d;
}

} // namespace et::baseline
