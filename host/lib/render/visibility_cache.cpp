#include "render/visibility_cache.h"

#include "util/error.h"

#include <algorithm>
#include <cmath>

namespace et {
namespace {

constexpr int K = ETK_GUIDE_REGIONS;
// Fixed point: a value of the map's power counts 2^28; one record at most 2^12 of that (a single
// sample that large is a firefly, not information), so a slot holds 2^24 such records.
constexpr double kUnit = 268435456.0; // 2^28
constexpr double kMaxValue = 4096.0;

} // namespace

std::vector<float> guide_region_tables(const std::vector<float>& dist, int w, int h) {
    std::vector<float> out(static_cast<size_t>(etk::etk_guide_regions_size(h)), 0.0f);
    const float* marginal = dist.data();
    const float* ccdf = dist.data() + etk::etk_dist2d_conditional_cdf(w, h);
    for (int r = 0; r < h; ++r)
        for (int j = 0; j <= ETK_GUIDE_SUBBANDS; ++j)
            out[etk::etk_guide_split_table(r, h) + j] =
                ccdf[static_cast<size_t>(r) * (w + 1) + etk::etk_guide_sub_start(j, w)];
    std::vector<double> mass(K, 0.0);
    for (int Rc = 0; Rc < ETK_GUIDE_COLS; ++Rc) {
        const int c0 = etk::etk_guide_col_start(Rc, w), c1 = etk::etk_guide_col_start(Rc + 1, w);
        for (int Rr = 0; Rr < ETK_GUIDE_ROWS; ++Rr) {
            const int r0 = etk::etk_guide_row_start(Rr, h),
                      r1 = etk::etk_guide_row_start(Rr + 1, h);
            // Row r's share of the region: p(v_r) / h x the row's conditional mass in [c0, c1).
            std::vector<double> cum(r1 - r0 + 1, 0.0);
            for (int r = r0; r < r1; ++r) {
                const float* row = ccdf + static_cast<size_t>(r) * (w + 1);
                const double m = std::max(0.0, double(row[c1]) - double(row[c0]));
                cum[r - r0 + 1] = cum[r - r0] + double(marginal[r]) / h * m;
            }
            const double total = cum.back();
            mass[Rr * ETK_GUIDE_COLS + Rc] = total;
            float* t = out.data() + etk::etk_guide_row_table(Rr, Rc, h);
            for (int i = 0; i <= r1 - r0; ++i)
                t[i] = total > 0.0 ? static_cast<float>(cum[i] / total)
                                   : static_cast<float>(double(i) / std::max(1, r1 - r0));
            t[r1 - r0] = 1.0f;
        }
    }
    double all = 0.0;
    for (double m : mass)
        all += m;
    for (int R = 0; R < K; ++R)
        out[R] = all > 0.0 ? static_cast<float>(mass[R] / all) : 0.0f;
    return out;
}

double guide_map_power(const std::vector<float>& rgb, int w, int h) {
    double sum = 0.0;
    for (int y = 0; y < h; ++y) {
        const double sin_theta = std::sin(M_PI * (y + 0.5) / h);
        double row = 0.0;
        for (int x = 0; x < w; ++x) {
            const float* t = rgb.data() + 3 * (static_cast<size_t>(y) * w + x);
            row += 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2];
        }
        sum += row * sin_theta;
    }
    return sum * (2.0 * M_PI / w) * (M_PI / h);
}

namespace {

// A CDF over the regions from probabilities (summing to about 1): cdf[0] = 0, cdf[K] = 1.
void write_cdf(const std::vector<double>& prob, float* cdf) {
    double total = 0.0;
    for (double x : prob)
        total += x;
    double run = 0.0;
    cdf[0] = 0.0f;
    for (int R = 0; R < K; ++R) {
        run += prob[R];
        cdf[R + 1] = total > 0.0 ? static_cast<float>(run / total) : float(R + 1) / K;
    }
    cdf[K] = 1.0f;
}

} // namespace

size_t guide_cells_size(int slots, bool continuation) {
    return static_cast<size_t>(slots) *
           (ETK_GUIDE_CELL_FLOATS + (continuation ? ETK_GUIDE_DIR_FLOATS : 0));
}

std::vector<float> guide_prior_cells(const std::vector<float>& regions, int slots,
                                     bool continuation) {
    std::vector<double> prob(regions.begin(), regions.begin() + K);
    std::vector<float> light(ETK_GUIDE_CELL_FLOATS), dir(ETK_GUIDE_DIR_FLOATS, 0.0f);
    write_cdf(prob, light.data());
    write_cdf(std::vector<double>(K, 1.0), dir.data()); // uniform, share 0: not guided
    std::vector<float> out(guide_cells_size(slots, continuation));
    for (int s = 0; s < slots; ++s) {
        std::copy(light.begin(), light.end(),
                  out.begin() + static_cast<size_t>(s) * ETK_GUIDE_CELL_FLOATS);
        if (continuation)
            std::copy(dir.begin(), dir.end(), out.begin() + etk::etk_guide_dir_offset(slots, s));
    }
    return out;
}

VisibilityCache::VisibilityCache(const VisibilityOptions& options,
                                 const std::vector<float>& regions, double scale)
    : opt_(options), mass_(regions.begin(), regions.begin() + K),
      inv_scale_(scale > 0.0 ? 1.0 / scale : 1.0) {
    light_.sums.assign(static_cast<size_t>(options.slots) * K, 0);
    light_.counts.assign(options.slots, 0);
    if (options.continuation) {
        dir_.sums = light_.sums;
        dir_.counts = light_.counts;
    }
}

void VisibilityCache::add_to(RegionSums& to, const int* keys, const float* values, int n) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (to.sums.empty())
        throw Error("continuation records for a visibility cache built without the guide");
    for (int i = 0; i < n; ++i) {
        const int key = keys[i];
        if (key < 0 || key >= opt_.slots * K)
            continue;
        const double v = std::isfinite(values[i]) ? std::max(0.0, double(values[i])) : 0.0;
        to.sums[key] +=
            static_cast<uint64_t>(std::llround(std::min(v * inv_scale_, kMaxValue) * kUnit));
        ++to.counts[key / K];
        ++to.records;
    }
}

void VisibilityCache::add(const int* keys, const float* values, int n) {
    add_to(light_, keys, values, n);
}

void VisibilityCache::add_continuations(const int* keys, const float* values, int n) {
    add_to(dir_, keys, values, n);
}

std::vector<float> VisibilityCache::tables() const {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool continuation = !dir_.sums.empty();
    // Cells without records keep the prior tables (most cells of a scene).
    std::vector<float> out = guide_prior_cells(mass_, opt_.slots, continuation);
    std::vector<double> prob(K);
    const std::vector<float> uniform(K, 1.0f / K);
    // Slot s's P = own x S / sum S + (1 - own) x prior, own = n / (n + n0) (0 if nothing came
    // back); returns own.
    auto learned = [&](const RegionSums& r, int s, const std::vector<float>& prior) {
        const uint64_t* S = r.sums.data() + static_cast<size_t>(s) * K;
        double total = 0.0;
        for (int R = 0; R < K; ++R)
            total += double(S[R]);
        const double n = r.counts[s];
        const double own = total > 0.0 ? n / (n + opt_.prior) : 0.0;
        for (int R = 0; R < K; ++R)
            prob[R] = (own > 0.0 ? own * double(S[R]) / total : 0.0) + (1.0 - own) * prior[R];
        return own;
    };
    for (int s = 0; s < opt_.slots; ++s) {
        if (light_.counts[s] > 0) { // the light sample's mixture Q = alpha M + (1 - alpha) P
            learned(light_, s, mass_);
            for (int R = 0; R < K; ++R)
                prob[R] = opt_.alpha * mass_[R] + (1.0 - opt_.alpha) * prob[R];
            write_cdf(prob, out.data() + static_cast<size_t>(s) * ETK_GUIDE_CELL_FLOATS);
        }
        if (continuation && dir_.counts[s] > 0) { // the continuation guide and its share
            float* dir = out.data() + etk::etk_guide_dir_offset(opt_.slots, s);
            const double own = learned(dir_, s, uniform);
            write_cdf(prob, dir);
            dir[ETK_GUIDE_DIR_SHARE] = static_cast<float>(opt_.continuation_share * own);
        }
    }
    return out;
}

bool VisibilityCache::update_after(int pass, int learning_passes) {
    const int done = pass + 1;
    return done == learning_passes || (done & (done - 1)) == 0;
}

} // namespace et
