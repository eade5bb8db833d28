#include "render/visibility_cache.h"

#include "kernels/continuation_guide.h"
#include "util/error.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace et {
namespace {

constexpr int K = ETK_GUIDE_REGIONS;
// The records' cap (kernels/visibility_record.h): a second moment of a density of 0.
constexpr double kMaxValue = ETK_GUIDE_MAX_RECORD;

} // namespace

VisibilityCache::VisibilityCache(const VisibilityOptions& options,
                                 const std::vector<float>& regions, double scale,
                                 const std::array<float, 6>& box)
    : opt_(options), mass_(regions.begin(), regions.begin() + K), box_(box),
      portal_(ETK_PORTAL_CELLS, 0),
      moments_(static_cast<size_t>(options.slots) * ETK_PORTAL_CANDIDATES, 0),
      shares_(options.slots, 0.0f), light_m2_(options.slots, 0),
      last_(guide_prior_cells(mass_, options.slots, options.continuation, box)),
      inv_power_(guide_inv_power(scale)) {
    for (int j = 0; j < ETK_PORTAL_CANDIDATES; ++j)
        portal_candidates_[j] = etk::etk_portal_candidate(j);
    light_.sums.assign(static_cast<size_t>(options.slots) * K, 0);
    light_.counts.assign(options.slots, 0);
    light_.counted = light_.counts;
    if (options.continuation) {
        dir_.sums = light_.sums;
        dir_.counts = light_.counts;
        dir_.counted = light_.counts;
        spot_.assign(ETK_PORTAL_CELLS, 0);
        spot_moments_.assign(static_cast<size_t>(options.slots) * options.spot_shares.size(), 0);
        spot_shares_.assign(options.slots, 0.0f);
        guided_moments_.assign(static_cast<size_t>(options.slots) * options.guided_shares.size(),
                               0);
        guided_shares_.assign(options.slots, static_cast<float>(options.continuation_share));
        guided_records_.assign(options.slots, 0);
        cont_m2_.assign(options.slots, 0);
    }
}

namespace {

// v >= 0 in the device's fixed point, so that both kinds of records sum in one unit.
uint64_t fixed_point(double v) {
    return etk::etk_guide_fixed(static_cast<float>(v));
}

double record_value(float v) {
    return std::isfinite(v) ? std::max(0.0, double(v)) : 0.0;
}

// The lanes of a pass add their records concurrently, straight into the sums: integer additions
// commute, so the sums do not depend on which lane adds first (tables() reads them between
// passes, when no lane adds).
template <typename T> void add_to(std::vector<T>& sums, size_t i, T v) {
    __atomic_fetch_add(&sums[i], v, __ATOMIC_RELAXED);
}

// The box-cell tables are small and both lanes add to the same cells (a window's): atomic adds
// there would pass their lines back and forth between cores. A call's records are summed per
// cell in the thread's own dense copy, and each touched cell is added once.
class CellBatch {
  public:
    CellBatch() { sums_.resize(ETK_PORTAL_CELLS, 0); }
    void add(int cell, uint64_t v) {
        if (v == 0)
            return;
        if (sums_[cell] == 0)
            touched_.push_back(cell);
        sums_[cell] += v;
    }
    void flush(std::vector<uint64_t>& to) {
        for (int c : touched_) {
            add_to(to, static_cast<size_t>(c), sums_[c]);
            sums_[c] = 0;
        }
        touched_.clear();
    }

  private:
    std::vector<uint64_t> sums_;
    std::vector<int> touched_;
};

// Records arrive in queue order, their keys scattered over megabytes of sums: each atomic add
// waits for its line. The lines of the record kPrefetch ahead are requested first.
constexpr int kPrefetch = 8;

} // namespace

int VisibilityCache::add_region(RegionSums& to, int key, double v) {
    const int s = key / K;
    add_to(to.sums, static_cast<size_t>(key), fixed_point(v));
    add_to(to.counts, static_cast<size_t>(s), 1u);
    return s;
}

void VisibilityCache::add(const int* keys, const float* values, const int* exits,
                          const float* parts, int n) {
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (pending_.empty())
            pending_.assign(static_cast<size_t>(etk::etk_gsum_words(opt_.slots)), 0u);
    }
    etk::EtkParams p{};
    p.guide_slots = opt_.slots;
    p.guide_inv_power = inv_power_;
    const float* box = last_.data() + etk::etk_portal_offset(opt_.slots, opt_.continuation);
    for (int i = 0; i < n; ++i)
        etk::etk_guide_record_light(pending_.data(), p, box, keys[i], values[i], exits[i],
                                    etk::make_float2(parts[2 * i], parts[2 * i + 1]));
}

namespace {

uint64_t wide(const uint32_t* w) {
    return uint64_t(w[0]) | uint64_t(w[1]) << 32;
}

} // namespace

void VisibilityCache::absorb(const std::vector<uint32_t>& words) {
    const int S = opt_.slots;
    if (words.size() != static_cast<size_t>(etk::etk_gsum_words(S)))
        throw Error("visibility record sums of " + std::to_string(words.size()) +
                    " words, expected " + std::to_string(etk::etk_gsum_words(S)));
    const uint32_t* w = words.data();
    for (int s = 0; s < S; ++s) {
        const uint32_t n = w[etk::etk_gsum_counts(S) + s];
        if (n == 0)
            continue; // no record: nothing summed in the cell (most cells)
        light_.counts[s] += n;
        light_m2_[s] += wide(w + etk::etk_gsum_m2(S) + 2 * s);
        for (size_t k = size_t(s) * K; k < size_t(s + 1) * K; ++k)
            light_.sums[k] += wide(w + 2 * k);
    }
    for (size_t k = 0; k < moments_.size(); ++k)
        moments_[k] += wide(w + etk::etk_gsum_moments(S) + 2 * k);
    for (int c = 0; c < ETK_PORTAL_CELLS; ++c)
        portal_[c] += wide(w + etk::etk_gsum_portal(S) + 2 * c);
    light_.records += wide(w + etk::etk_gsum_records(S));
}

void VisibilityCache::add_continuations(const int* keys, const float* values, const float* rays,
                                        int n) {
    if (dir_.sums.empty())
        throw Error("continuation records for a visibility cache built without the guide");
    const size_t C = opt_.spot_shares.size(), G = opt_.guided_shares.size();
    // The tables the records were drawn with (last_ only changes in tables(), between passes).
    const float* spot =
        last_.data() + etk::etk_portal_offset(opt_.slots, 1) + etk::etk_portal_size(opt_.slots);
    const float c1 = static_cast<float>(opt_.continuation_share);
    uint64_t records = 0;
    thread_local CellBatch cells;
    for (int i = 0; i < n; ++i) {
        if (i + kPrefetch < n && keys[i + kPrefetch] >= 0 && keys[i + kPrefetch] < opt_.slots * K) {
            const int k = keys[i + kPrefetch], ks = k / K;
            __builtin_prefetch(&dir_.sums[static_cast<size_t>(k)], 1);
            __builtin_prefetch(&spot_moments_[ks * C], 1);
            __builtin_prefetch(&guided_moments_[ks * G], 1);
            __builtin_prefetch(&cont_m2_[ks], 1);
            // The record's region entries of the cell's table (its key's region is its ray's).
            __builtin_prefetch(&last_[etk::etk_guide_dir_offset(opt_.slots, ks) + k % K], 0);
        }
        const int key = keys[i];
        if (key < 0 || key >= opt_.slots * K)
            continue;
        ++records;
        const double v = record_value(values[i]) * inv_power_; // relative to the map's power
        const int s = key / K;
        const float* r = rays + 8 * static_cast<size_t>(i);
        const etk::float3 o = etk::make_float3(r[0], r[1], r[2]);
        const etk::float3 d = etk::make_float3(r[4], r[5], r[6]);
        float t;
        const int exit = etk::etk_portal_exit(spot, o, d, &t);
        // The densities the record was drawn with: the cell's guide, the spot table, the BSDF's.
        const float* dir = last_.data() + etk::etk_guide_dir_offset(opt_.slots, s);
        const float c = dir[ETK_GUIDE_DIR_SHARE];
        const float q = spot[ETK_PORTAL_ON] > 0.0f ? spot[ETK_PORTAL_SHARES + s] : 0.0f;
        const float pg = etk::etk_cguide_region_pdf(dir, d);
        const float ps = etk::etk_portal_pdf_exit(spot, d, exit, t);
        const double prec = r[7];
        // p_b from the mixture the record was drawn with (its BSDF part taken out).
        const double pb =
            c < 1.0f ? std::max(0.0, (prec - etk::etk_cguide_mix(c, q, pg, ps, 0.0f)) / (1.0 - c))
                     : 0.0;
        // What the tables learn: luminance(L_in) cos / p = pi p_b v (p_b = cos / pi at a diffuse
        // vertex, the only kind that is guided), so that both tables follow the integrand's
        // incident radiance x cosine rather than the radiance alone. A glossy vertex's record,
        // drawn from its lobe alone (p_rec = its p_b, but recovered here with the cell's share c),
        // weighs at most pi luminance(L_in) / (1 - c): bounded, as its radiance alone weighed.
        const double g = std::isfinite(pb) ? M_PI * pb * v : 0.0;
        add_region(dir_, key, g);
        if (exit >= 0 && exit < ETK_PORTAL_CELLS)
            cells.add(exit, fixed_point(g));
        if (!(v > 0.0) || !(pb > 0.0) || !std::isfinite(prec * ps * pg))
            continue;
        // The continuation's estimate at a diffuse vertex, f cos L / p = albedo p_bsdf v (p_bsdf =
        // cos / pi): its second moment in light_sample_count's unit.
        add_to(cont_m2_, static_cast<size_t>(s), fixed_point(pb * v * pb * v));
        for (size_t j = 0; j < C; ++j) {
            const double pq = etk::etk_cguide_mix(c1, static_cast<float>(opt_.spot_shares[j]), pg,
                                                  ps, static_cast<float>(pb));
            const double m = pq > 0.0 ? v * v * prec * pb * pb / pq : kMaxValue;
            add_to(spot_moments_, s * C + j, fixed_point(m));
        }
        // The guided share's moments, with the cell's spot share; from the first update on (the
        // prior guide is uniform: its records would only tell that it is worse than the BSDF).
        if (guide_learned_)
            add_to(guided_records_, static_cast<size_t>(s), 1u);
        for (size_t j = 0; j < G && guide_learned_; ++j) {
            const double pc = etk::etk_cguide_mix(static_cast<float>(opt_.guided_shares[j]), q, pg,
                                                  ps, static_cast<float>(pb));
            const double m = pc > 0.0 ? v * v * prec * pb * pb / pc : kMaxValue;
            add_to(guided_moments_, s * G + j, fixed_point(m));
        }
    }
    cells.flush(spot_);
    __atomic_fetch_add(&dir_.records, records, __ATOMIC_RELAXED);
}

double light_sample_count(double m_light, double m_cont, double cost, const double* counts,
                          size_t n) {
    auto model = [&](double c) { return (m_cont + m_light / c) * (1.0 + cost * c); };
    double best = counts[0];
    for (size_t j = 1; j < n; ++j)
        best = model(counts[j]) < model(best) ? counts[j] : best;
    return best;
}

size_t least_moment_share(const uint64_t* moments, size_t n, double cost) {
    size_t best = 0;
    double least = double(moments[0]);
    for (size_t j = 1; j < n; ++j) {
        const double m = double(moments[j]) / (1.0 - cost);
        best = m < least ? j : best; // a tie keeps the smaller share
        least = std::min(m, least);
    }
    return best;
}

void VisibilityCache::choose_shares(const double* candidates, size_t n, double cost, RegionSums& r,
                                    std::vector<uint64_t>& moments, std::vector<float>& shares) {
    for (int s = 0; s < opt_.slots; ++s) {
        if (r.counts[s] - r.counted[s] >= static_cast<uint32_t>(opt_.min_records))
            shares[s] =
                static_cast<float>(candidates[least_moment_share(moments.data() + s * n, n, cost)]);
        r.counted[s] = r.counts[s];
        std::fill(moments.begin() + s * n, moments.begin() + (s + 1) * n, 0);
    }
}

void VisibilityCache::choose_guided_shares() {
    const size_t G = opt_.guided_shares.size();
    for (int s = 0; s < opt_.slots; ++s)
        if (guided_records_[s] >= static_cast<uint32_t>(opt_.min_records))
            guided_shares_[s] = static_cast<float>(
                opt_.guided_shares[least_moment_share(guided_moments_.data() + s * G, G, 0.0)]);
}

const std::vector<float>& VisibilityCache::tables() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!pending_.empty()) { // the records add() summed since the last update
        absorb(pending_);
        std::fill(pending_.begin(), pending_.end(), 0u);
    }
    choose_shares(portal_candidates_.data(), ETK_PORTAL_CANDIDATES, 0.0, light_, moments_, shares_);
    const bool continuation = !dir_.sums.empty();
    if (continuation) // before the cells' tables, which take the shares
        choose_guided_shares();
    fewer_.clear();
    // Rebuilt in place (34 MB at 2^13 slots: a fresh copy each update, its pages faulted in and
    // then copied to last_, was most of an update's 29 ms). Cells without records keep the
    // prior tables (most cells of a scene); a cell's counts only grow, so every part of a cell
    // an earlier update wrote is written again below: the same tables as built afresh.
    std::vector<float>& out = last_;
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
            float* cell = out.data() + static_cast<size_t>(s) * ETK_GUIDE_CELL_FLOATS;
            write_guide_cdf(prob, cell);
            const uint32_t nl = light_.counts[s], nc = continuation ? dir_.counts[s] : 0;
            const auto min_records = static_cast<uint32_t>(opt_.min_records);
            const float count =
                nl >= min_records && nc >= min_records
                    ? static_cast<float>(light_sample_count(
                          double(light_m2_[s]) / nl, double(cont_m2_[s]) / nc, opt_.light_cost,
                          opt_.light_counts.data(), opt_.light_counts.size()))
                    : 1.0f;
            cell[ETK_GUIDE_LIGHT_COUNT] = count;
            if (count < 1.0f)
                ++fewer_[count];
        }
        if (continuation && dir_.counts[s] > 0) { // the continuation guide and its share
            float* dir = out.data() + etk::etk_guide_dir_offset(opt_.slots, s);
            const double own = learned(dir_, s, uniform);
            write_guide_cdf(prob, dir);
            dir[ETK_GUIDE_DIR_SHARE] = static_cast<float>(guided_shares_[s] * own);
        }
    }
    float* portal = out.data() + etk::etk_portal_offset(opt_.slots, continuation ? 1 : 0);
    write_portal_table(box_, shares_, std::vector<double>(portal_.begin(), portal_.end()), portal);
    if (continuation) {
        choose_shares(opt_.spot_shares.data(), opt_.spot_shares.size(), opt_.spot_cost, dir_,
                      spot_moments_, spot_shares_);
        write_portal_table(box_, spot_shares_, std::vector<double>(spot_.begin(), spot_.end()),
                           portal + etk::etk_portal_size(opt_.slots));
    }
    guide_learned_ = true;
    return out;
}

bool VisibilityCache::update_after(int pass, int learning_passes) {
    const int done = pass + 1;
    return done == learning_passes || (done & (done - 1)) == 0;
}

} // namespace et
