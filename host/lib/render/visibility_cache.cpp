#include "render/visibility_cache.h"

#include "kernels/continuation_guide.h"
#include "util/error.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace et {
namespace {

constexpr int K = ETK_GUIDE_REGIONS;

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
    for (int j = 0; j < ETK_GUIDED_CANDIDATES; ++j)
        guided_candidates_[j] = etk::etk_guided_candidate(j);
    light_.sums.assign(static_cast<size_t>(options.slots) * K, 0);
    light_.counts.assign(options.slots, 0);
    light_.counted = light_.counts;
    if (options.continuation) {
        dir_.sums = light_.sums;
        dir_.counts = light_.counts;
        dir_.counted = light_.counts;
        spot_.assign(ETK_PORTAL_CELLS, 0);
        spot_moments_.assign(static_cast<size_t>(options.slots) * ETK_PORTAL_CANDIDATES, 0);
        spot_shares_.assign(options.slots, 0.0f);
        guided_moments_.assign(static_cast<size_t>(options.slots) * ETK_GUIDED_CANDIDATES, 0);
        guided_shares_.assign(options.slots, static_cast<float>(options.continuation_share));
        guided_records_.assign(options.slots, 0);
        cont_m2_.assign(options.slots, 0);
    }
}

// The host's records go through the device's own functions (kernels/visibility_record.h) into a
// block of the device's layout, absorbed at the next tables().
etk::EtkParams VisibilityCache::record_params() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (pending_.empty())
        pending_.assign(static_cast<size_t>(etk::etk_gsum_words(opt_.slots, opt_.continuation)),
                        0u);
    etk::EtkParams p{};
    p.guide_slots = opt_.slots;
    p.guide_inv_power = inv_power_;
    p.guide_continuation = opt_.continuation ? 1 : 0;
    p.guide_continuation_share = static_cast<float>(opt_.continuation_share);
    p.guide_ready = guide_learned_ ? 1 : 0;
    return p;
}

void VisibilityCache::add(const int* keys, const float* values, const int* exits,
                          const float* parts, int n, const float* reaches) {
    const etk::EtkParams p = record_params();
    const float* box = last_.data() + etk::etk_portal_offset(opt_.slots, opt_.continuation);
    for (int i = 0; i < n; ++i)
        etk::etk_guide_record_light(pending_.data(), p, box, keys[i], values[i],
                                    reaches ? reaches[i] : values[i], exits[i],
                                    etk::make_float2(parts[2 * i], parts[2 * i + 1]));
}

void VisibilityCache::add_continuations(const int* keys, const float* values, const float* rays,
                                        int n) {
    if (!opt_.continuation)
        throw Error("continuation records for a visibility cache built without the guide");
    const etk::EtkParams p = record_params();
    for (int i = 0; i < n; ++i) {
        const float* r = rays + 8 * static_cast<size_t>(i);
        etk::etk_guide_record_continuation(pending_.data(), p, last_.data(), keys[i], values[i],
                                           etk::make_float3(r[0], r[1], r[2]),
                                           etk::make_float3(r[4], r[5], r[6]), r[7]);
    }
}

namespace {

uint64_t wide(const uint32_t* w) {
    return uint64_t(w[0]) | uint64_t(w[1]) << 32;
}

// Adds the pairs w[2 k], w[2 k + 1] to to[k], k < n, and zeroes them; returns their sum.
double take_pairs(uint64_t* to, uint32_t* w, size_t n) {
    double taken = 0.0;
    for (size_t k = 0; k < n; ++k) {
        const uint64_t v = wide(w + 2 * k);
        to[k] += v;
        taken += double(v);
    }
    std::fill(w, w + 2 * n, 0u);
    return taken;
}

} // namespace

// One kind of records of cell s: its count, second moment and region sums (regions: the kind's
// slots x K pairs), added to r and m2 and zeroed. A cell without records has nothing summed.
void VisibilityCache::absorb_cell(RegionSums& r, uint64_t& m2, int s, uint32_t* regions,
                                  uint32_t* count, uint32_t* moment) {
    if (*count == 0)
        return;
    r.counts[s] += *count;
    r.records += *count;
    *count = 0;
    take_pairs(&m2, moment, 1);
    r.total += take_pairs(r.sums.data() + size_t(s) * K, regions + 2 * size_t(s) * K, K);
}

void VisibilityCache::absorb(uint32_t* words, size_t count) {
    const int S = opt_.slots, C = opt_.continuation ? 1 : 0;
    const size_t expected = static_cast<size_t>(etk::etk_gsum_words(S, C));
    if (count != expected)
        throw Error("visibility record sums of " + std::to_string(count) + " words, expected " +
                    std::to_string(expected));
    const size_t P = ETK_PORTAL_CANDIDATES, G = ETK_GUIDED_CANDIDATES;
    for (int s = 0; s < S; ++s) {
        uint32_t* cell = words + etk::etk_gsum_cell(S, C, s);
        if (cell[ETK_GSUM_COUNT] == 0 && (!C || cell[ETK_GSUM_DCOUNT] == 0))
            continue;       // no record: nothing summed in the cell (most cells)
        uint64_t reach = 0; // what the cell's shadow rays would have found unblocked
        light_reach_ += take_pairs(&reach, cell + ETK_GSUM_REACH, 1);
        absorb_cell(light_, light_m2_[s], s, words, cell + ETK_GSUM_COUNT, cell + ETK_GSUM_M2);
        take_pairs(moments_.data() + s * P, cell + ETK_GSUM_MOMENTS, P);
        if (!C)
            continue;
        absorb_cell(dir_, cont_m2_[s], s, words + etk::etk_gsum_dir(S, C), cell + ETK_GSUM_DCOUNT,
                    cell + ETK_GSUM_CM2);
        take_pairs(spot_moments_.data() + s * P, cell + ETK_GSUM_SPOTM, P);
        take_pairs(guided_moments_.data() + s * G, cell + ETK_GSUM_GUIDEDM, G);
        guided_records_[s] += cell[ETK_GSUM_GCOUNT];
        cell[ETK_GSUM_GCOUNT] = 0u;
    }
    take_pairs(portal_.data(), words + etk::etk_gsum_portal(S, C), portal_.size());
    if (C)
        take_pairs(spot_.data(), words + etk::etk_gsum_spot(S), spot_.size());
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
    const size_t G = ETK_GUIDED_CANDIDATES;
    for (int s = 0; s < opt_.slots; ++s)
        if (guided_records_[s] >= static_cast<uint32_t>(opt_.min_records))
            guided_shares_[s] = static_cast<float>(
                guided_candidates_[least_moment_share(guided_moments_.data() + s * G, G, 0.0)]);
}

const std::vector<float>& VisibilityCache::tables() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!pending_.empty()) // the records add() summed since the last update
        absorb(pending_.data(), pending_.size());
    const bool continuation = !dir_.sums.empty();
    // A slot's tables change only with records since the last update: its sums, counts, second
    // moments and shares move only with them (counted: the counts then).
    fresh_.resize(opt_.slots);
    for (int s = 0; s < opt_.slots; ++s)
        fresh_[s] = light_.counts[s] != light_.counted[s] ||
                    (continuation && dir_.counts[s] != dir_.counted[s]);
    choose_shares(portal_candidates_.data(), ETK_PORTAL_CANDIDATES, 0.0, light_, moments_, shares_);
    if (continuation) // before the cells' tables, which take the shares
        choose_guided_shares();
    fewer_.clear();
    // Rebuilt in place (34 MB at 2^13 slots: a fresh copy each update, its pages faulted in and
    // then copied to last_, was most of an update's 29 ms), fresh slots only. Cells without
    // records keep the prior tables (most cells of a scene), cells without new ones the tables
    // of the last update; a cell's counts only grow, so every part of a cell an earlier update
    // wrote is written again below: the same tables as built afresh.
    std::vector<float>& out = last_;
    // The floats rewritten: the fresh slots' light tables, their continuation tables, the
    // portal tables (adjacent spans merged).
    std::vector<FloatSpan> dir_changed;
    changed_.clear();
    auto changed = [](std::vector<FloatSpan>& spans, size_t first, size_t end) {
        if (!spans.empty() && spans.back().second == first)
            spans.back().second = end;
        else
            spans.emplace_back(first, end);
    };
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
        float* cell = out.data() + static_cast<size_t>(s) * ETK_GUIDE_CELL_FLOATS;
        if (light_.counts[s] > 0 && !fresh_[s] && cell[ETK_GUIDE_LIGHT_COUNT] < 1.0f)
            ++fewer_[cell[ETK_GUIDE_LIGHT_COUNT]];
        if (!fresh_[s])
            continue;
        if (light_.counts[s] > 0) { // the light sample's mixture Q = alpha M + (1 - alpha) P
            changed(changed_, static_cast<size_t>(s) * ETK_GUIDE_CELL_FLOATS,
                    static_cast<size_t>(s + 1) * ETK_GUIDE_CELL_FLOATS);
            learned(light_, s, mass_);
            for (int R = 0; R < K; ++R)
                prob[R] = opt_.alpha * mass_[R] + (1.0 - opt_.alpha) * prob[R];
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
            const size_t first = static_cast<size_t>(dir - out.data());
            changed(dir_changed, first, first + ETK_GUIDE_DIR_FLOATS);
        }
    }
    changed_.insert(changed_.end(), dir_changed.begin(), dir_changed.end());
    const size_t portals = etk::etk_portal_offset(opt_.slots, continuation ? 1 : 0);
    changed_.emplace_back(portals, out.size());
    float* portal = out.data() + portals;
    write_portal_table(box_, shares_, std::vector<double>(portal_.begin(), portal_.end()), portal);
    if (continuation) {
        choose_shares(portal_candidates_.data(), ETK_PORTAL_CANDIDATES, opt_.spot_cost, dir_,
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
