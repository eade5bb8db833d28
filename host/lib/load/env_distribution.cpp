#include "load/env_distribution.h"
#include "util/checked_size.h"
#include "util/error.h"
#include "util/file_check.h"
#include "util/parallel.h"
#include "util/prefault.h"

#include "kernels/piecewise_constant.h"

#include <algorithm>
#include <atomic>
#include <cmath>

// One streaming pass over the map, a row at a time: luminance into a wrap-padded row, the
// horizontal filter into a ring of 2r+1 filtered rows, the vertical filter (clamped at the poles)
// straight into the conditional-density rows of the table, then sin(theta) and the row's CDF
// while the row is still in cache. The only full-size buffer is the table itself. The arithmetic
// (operands, order of the float sums) is that of the straightforward separable filter and area
// resample, so the densities are bit-identical to it; the double prefix sums run as several
// independent chains and agree to double rounding (see prefix_sums).

namespace et {
namespace {

// The bilinear cell-mean taps [1 6 1]/8 convolved with a truncated, normalised Gaussian.
std::vector<float> filter_taps(float sigma) {
    std::vector<float> g{1.0f};
    sigma = std::min(sigma, kMaxBlurSigma); // callers check; this keeps the int cast defined
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

// Independent accumulation chains for the double prefix sums: a single chain is bound by the
// latency of a double add (about 4 cycles per element), several chains run in parallel.
constexpr int kChains = 8;

// local[i + 1] = sum of f over [segment start, i] for kChains contiguous segments of n / kChains
// elements and a short tail; seg_offset[j] = sum of f before segment j (kChains + 2 entries).
// Returns the sum of f. Every partial sum is exact to double rounding of float inputs.
template <typename T> double prefix_sums(const T* f, int n, double* local, double* seg_offset) {
    const int len = n / kChains;
    double acc[kChains] = {};
    for (int i = 0; i < len; ++i)
        for (int j = 0; j < kChains; ++j) {
            acc[j] += f[j * len + i];
            local[j * len + i + 1] = acc[j];
        }
    double tail = 0.0;
    for (int i = kChains * len; i < n; ++i) {
        tail += f[i];
        local[i + 1] = tail;
    }
    double run = 0.0;
    for (int j = 0; j < kChains; ++j) {
        seg_offset[j] = run;
        run += acc[j];
    }
    seg_offset[kChains] = run;
    run += tail;
    seg_offset[kChains + 1] = run;
    return run;
}

// build_piecewise_constant_1d with pdf allowed to alias f, using scratch of n + 1 doubles. f is
// float (a row) or double (the row masses of the marginal).
template <typename T> double build_1d(const T* f, int n, float* pdf, float* cdf, double* local) {
    double seg_offset[kChains + 2];
    const double sum = prefix_sums(f, n, local, seg_offset);
    cdf[0] = 0.0f;
    // Every interval with mass keeps at least kMinCdfShare of the CDF (env_distribution.h).
    double floored_sum = sum;
    std::vector<double> floored;
    if (sum > 0.0) {
        const double floor = sum * kMinCdfShare;
        for (int i = 0; i < n && floored.empty(); ++i)
            if (f[i] > 0 && f[i] < floor)
                floored.assign(f, f + n);
        if (!floored.empty()) {
            for (double& v : floored)
                v = raised_to_least_share(v, floor);
            floored_sum = prefix_sums(floored.data(), n, local, seg_offset);
        }
    }
    if (!(sum > 0.0)) {
        // No mass: a linear CDF keeps the binary search well defined; densities stay zero.
        for (int i = 0; i < n; ++i) {
            pdf[i] = 0.0f;
            cdf[i + 1] = static_cast<float>(i + 1) / n;
        }
        cdf[n] = 1.0f;
        return 0.0;
    }
    const double inv = 1.0 / floored_sum;
    // The densities f n / sum in double: n / sum alone overflows a float when the sum is below
    // n / FLT_MAX (1e-34 for n = 65536; texels of 1e-44 occur, fuzz finding F6), while each
    // density is at most n.
    const double density_scale = n / sum;
    const int len = n / kChains;
    for (int j = 0; j <= kChains; ++j) {
        const int begin = j * len, end = j < kChains ? begin + len : n;
        const double off = seg_offset[j];
        for (int i = begin; i < end; ++i) {
            pdf[i] = static_cast<float>(f[i] * density_scale);
            cdf[i + 1] = static_cast<float>((off + local[i + 1]) * inv);
        }
    }
    // Float rounding of a monotone double sequence is monotone; pin the end exactly.
    cdf[n] = 1.0f;
    return sum;
}

// Everything that depends only on the map and the options, shared by the worker threads.
struct Plan {
    int w, h, dw, dh, r, k;
    float exponent; // luminance^exponent is the function filtered (DistributionOptions)
    std::vector<float> taps;
    bool resampled;
    std::vector<Span> sx, sy;
    float* cond_pdf;
    float* cond_cdf;
    float* cond_guide;
    double* row_mass; // double: a float would round a row of denormal densities to 0
};

// Works on distribution rows [o0, o1): filters the input rows they need, writes their densities
// and CDFs and their masses. Rows are independent, so ranges can run on separate threads.
void build_rows(const Plan& p, const float* rgb, int o0, int o1) {
    if (o0 >= o1)
        return;
    const int w = p.w, h = p.h, dw = p.dw, dh = p.dh, r = p.r, k = p.k;
    const float* taps = p.taps.data();

    // Input rows needed: the area spans of the output rows (all of [o0, o1) without resampling).
    int y0 = o0, y1 = o1;
    if (p.resampled) {
        y0 = p.sy[o0].first;
        y1 = p.sy[o1 - 1].first + static_cast<int>(p.sy[o1 - 1].weights.size());
    }

    std::vector<float> pad(static_cast<size_t>(w) + 2 * r);
    std::vector<float> ring(static_cast<size_t>(k) * w);
    std::vector<float> vrow(p.resampled ? w : 0), hres(p.resampled ? dw : 0);
    std::vector<double> scratch(static_cast<size_t>(std::max(w, dw)) + 1);
    int next = std::max(0, y0 - r); // next input row to filter horizontally into the ring

    // Horizontal pass of input row sy (wraps around in phi) into its ring slot.
    auto filter_row = [&](int sy) {
        const float* src = rgb + 3 * static_cast<size_t>(sy) * w;
        float* lum = pad.data() + r;
        if (p.exponent == 1.0f)
            for (int x = 0; x < w; ++x)
                lum[x] = luminance(src + 3 * x);
        else
            for (int x = 0; x < w; ++x)
                lum[x] = std::pow(luminance(src + 3 * x), p.exponent);
        for (int x = 0; x < r; ++x) {
            pad[x] = lum[((x - r) % w + w) % w];
            pad[w + r + x] = lum[x % w];
        }
        float* out = &ring[static_cast<size_t>(sy % k) * w];
        std::fill(out, out + w, 0.0f);
        for (int t = 0; t < k; ++t) {
            const float wt = taps[t];
            const float* s = pad.data() + t;
            for (int x = 0; x < w; ++x)
                out[x] += wt * s[x];
        }
    };

    // The sin(theta)-weighted function of distribution row o, in place, then its tables.
    auto finish_row = [&](int o, float* fr) {
        const float sin_theta = std::sin(static_cast<float>(M_PI) * (o + 0.5f) / dh);
        for (int x = 0; x < dw; ++x)
            fr[x] = std::max(0.0f, fr[x]) * sin_theta; // max: filters never go negative, NaN-safe
        float* cdf = p.cond_cdf + static_cast<size_t>(o) * (dw + 1);
        p.row_mass[o] = build_1d(fr, dw, fr, cdf, scratch.data());
        // The row's guide while its CDF is still in cache.
        build_cdf_guide(cdf, dw,
                        p.cond_guide + static_cast<size_t>(o) * (etk::etk_guide_cells(dw) + 1));
    };

    int o_next = o0; // resampled case: first output row not yet finished
    for (int y = y0; y < y1; ++y) {
        for (; next <= std::min(y + r, h - 1); ++next)
            filter_row(next);
        // Vertical pass (clamped at the poles).
        float* dst = p.resampled ? vrow.data() : p.cond_pdf + static_cast<size_t>(y) * dw;
        std::fill(dst, dst + w, 0.0f);
        for (int t = 0; t < k; ++t) {
            const int sy = std::clamp(y + t - r, 0, h - 1);
            const float wt = taps[t];
            const float* src = &ring[static_cast<size_t>(sy % k) * w];
            for (int x = 0; x < w; ++x)
                dst[x] += wt * src[x];
        }
        if (!p.resampled) {
            finish_row(y, dst);
            continue;
        }
        // Area resample: across the row, then accumulated into the output rows whose span holds
        // input row y, in increasing y as a row-by-row vertical pass would.
        for (int x = 0; x < dw; ++x) {
            const Span& s = p.sx[x];
            float acc = 0.0f;
            for (size_t i = 0; i < s.weights.size(); ++i)
                acc += s.weights[i] * vrow[s.first + i];
            hres[x] = acc;
        }
        for (int o = o_next; o < o1 && p.sy[o].first <= y; ++o) {
            const Span& s = p.sy[o];
            const int i = y - s.first;
            if (i >= static_cast<int>(s.weights.size()))
                continue;
            const float wt = s.weights[i];
            float* out = p.cond_pdf + static_cast<size_t>(o) * dw;
            for (int x = 0; x < dw; ++x)
                out[x] += wt * hres[x];
        }
        // Output rows whose span ends at or before y + 1 are complete.
        while (o_next < o1 &&
               p.sy[o_next].first + static_cast<int>(p.sy[o_next].weights.size()) <= y + 1) {
            finish_row(o_next, p.cond_pdf + static_cast<size_t>(o_next) * dw);
            ++o_next;
        }
    }
    for (; o_next < o1 && p.resampled; ++o_next)
        finish_row(o_next, p.cond_pdf + static_cast<size_t>(o_next) * dw);
}

} // namespace

uint64_t distribution_table_entries(int w, int h) {
    // 2h + 1 + h (2w + 1) + guides, as etk_dist2d_size but without 32-bit overflow.
    const uint64_t W = static_cast<uint64_t>(std::max(w, 0)),
                   H = static_cast<uint64_t>(std::max(h, 0));
    const uint64_t KW = static_cast<uint64_t>(etk::etk_guide_cells(std::max(w, 0))),
                   KH = static_cast<uint64_t>(etk::etk_guide_cells(std::max(h, 0)));
    return 2 * H + 1 + H * (2 * W + 1) + (KH + 1) + H * (KW + 1);
}

void check_distribution_size(int w, int h) {
    const std::string res = std::to_string(w) + "x" + std::to_string(h);
    if (w < 1 || h < 1 || w > kMaxDistributionSide || h > kMaxDistributionSide)
        throw Error("distribution resolution " + res + " is out of range (1 to " +
                    std::to_string(kMaxDistributionSide) + " cells each way)");
    const uint64_t entries = distribution_table_entries(w, h);
    if (entries > kMaxDeviceIndex)
        throw Error("distribution resolution " + res + " needs " + std::to_string(entries) +
                    " table entries, more than the device indexes (" +
                    std::to_string(kMaxDeviceIndex) + "); use fewer cells");
    const uint64_t bytes = checked_mul(entries, sizeof(float), "distribution " + res);
    if (bytes > kMaxBufferBytes)
        throw Error("distribution resolution " + res + " needs " + byte_text(bytes) +
                    ", more than the memory budget of " + byte_text(kMaxBufferBytes) +
                    " per buffer; use fewer cells");
}

void build_cdf_guide(const float* cdf, int n, float* guide) {
    // guide[k] = the largest i < n with cdf[i] <= k / K, what etk_find_interval returns.
    // cdf[i] <= k / K exactly when ceil(cdf[i] K) <= k (K a power of two: the product is exact),
    // so entry i is written into cell ceil(cdf[i] K) in increasing i (the largest i of a cell
    // stays) and a running maximum fills the cells no entry starts in. Stores only and a max
    // chain: no data-dependent branch and no load after store to the same cell (a walk with a
    // comparison per step, or counting into the cells, doubled the distribution build).
    const int K = etk::etk_guide_cells(n);
    const float scale = static_cast<float>(K);
    std::fill(guide, guide + K + 1, 0.0f);
    for (int i = 1; i < n; ++i)
        guide[static_cast<int>(std::ceil(cdf[i] * scale))] = static_cast<float>(i); // cdf <= 1
    for (int k = 1; k < K; ++k)
        guide[k] = std::max(guide[k], guide[k - 1]);
    guide[K] = static_cast<float>(n - 1);
}

double build_piecewise_constant_1d(const float* f, int n, float* pdf, float* cdf) {
    std::vector<double> scratch(static_cast<size_t>(std::max(n, 0)) + 1);
    return build_1d(f, n, pdf, cdf, scratch.data());
}

struct DistributionBuilder::State {
    Plan p;
    EnvDistribution d;
    std::vector<double> row_mass;
    std::vector<int> block_start; // first distribution row of each block, then dh
};

DistributionBuilder::DistributionBuilder(int width, int height, const DistributionOptions& options)
    : s_(std::make_unique<State>()) {
    Plan& p = s_->p;
    p.w = width;
    p.h = height;
    p.dw = options.width > 0 ? options.width : p.w;
    p.dh = options.height > 0 ? options.height : p.h;
    check_distribution_size(p.dw, p.dh); // 32-bit offsets below are then exact
    if (p.w < 1 || p.h < 1)
        throw Error("a map of " + std::to_string(p.w) + "x" + std::to_string(p.h) +
                    " texels has no distribution");
    p.taps = filter_taps(options.blur_sigma);
    if (!(options.exponent >= kMinDistributionExponent && options.exponent <= 1.0f))
        throw Error("a distribution exponent of " + std::to_string(options.exponent) +
                    " is out of range [" + std::to_string(kMinDistributionExponent) + ", 1]");
    p.exponent = options.exponent;
    p.k = static_cast<int>(p.taps.size());
    p.r = p.k / 2;
    p.resampled = p.dw != p.w || p.dh != p.h;
    if (p.resampled) {
        p.sx = area_weights(p.w, p.dw);
        p.sy = area_weights(p.h, p.dh);
    }

    EnvDistribution& d = s_->d;
    d.width = p.dw;
    d.height = p.dh;
    d.table = prefaulted_vector<float>(distribution_table_entries(p.dw, p.dh));
    p.cond_pdf = d.table.data() + etk::etk_dist2d_conditional_pdf(p.dh);
    p.cond_cdf = d.table.data() + etk::etk_dist2d_conditional_cdf(p.dw, p.dh);
    p.cond_guide = d.table.data() + etk::etk_dist2d_conditional_guide(p.dw, p.dh);
    s_->row_mass.assign(p.dh, 0.0);
    p.row_mass = s_->row_mass.data();

    // Blocks of about 256 map rows (more for wide filters): each block filters the 2r rows around
    // it once more, a few percent here, and a map still decoding is followed closely.
    const int64_t map_rows = std::max(256, 8 * p.k);
    const int rows = static_cast<int>(std::clamp<int64_t>(map_rows * p.dh / p.h, 1, p.dh));
    for (int o = 0; o < p.dh; o += rows)
        s_->block_start.push_back(o);
    s_->block_start.push_back(p.dh);
}

DistributionBuilder::~DistributionBuilder() = default;

int DistributionBuilder::blocks() const {
    return static_cast<int>(s_->block_start.size()) - 1;
}

int DistributionBuilder::rows_needed(int block) const {
    const Plan& p = s_->p;
    const int o1 = s_->block_start[block + 1];
    const int y1 =
        p.resampled ? p.sy[o1 - 1].first + static_cast<int>(p.sy[o1 - 1].weights.size()) : o1;
    return std::min(p.h, y1 + p.r);
}

void DistributionBuilder::build_block(const float* rgb, int block) {
    build_rows(s_->p, rgb, s_->block_start[block], s_->block_start[block + 1]);
}

EnvDistribution DistributionBuilder::finish() {
    const Plan& p = s_->p;
    EnvDistribution d = std::move(s_->d);
    std::vector<double> scratch(static_cast<size_t>(p.dh) + 1);
    d.total = build_1d(s_->row_mass.data(), p.dh, d.table.data(),
                       d.table.data() + etk::etk_dist2d_marginal_cdf(p.dh), scratch.data());
    build_cdf_guide(d.table.data() + etk::etk_dist2d_marginal_cdf(p.dh), p.dh,
                    d.table.data() + etk::etk_dist2d_marginal_guide(p.dw, p.dh));
    s_.reset();
    return d;
}

EnvDistribution build_env_distribution(const RgbImage& image, const DistributionOptions& options) {
    DistributionBuilder builder(image.width, image.height, options);
    const int blocks = builder.blocks();
    const int threads = std::clamp(thread_count(options.threads), 1, blocks);
    std::atomic<int> next{0};
    run_on_threads(threads, [&](int) {
        for (int b = next++; b < blocks; b = next++)
            builder.build_block(image.rgb.data(), b);
    });
    return builder.finish();
}

} // namespace et
