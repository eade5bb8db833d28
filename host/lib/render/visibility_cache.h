// The visibility strategy's learning between passes (kernels/visibility_guide.h), on the host:
// the records' sums and the tables built from them. The tables before any learning, the map's
// region tables and the options are preparation's (prepare/visibility_tables.h).
//
// Learning: during the learning passes (samples 0 .. L-1, L = 64) every shadow ray of the
// visibility strategy leaves a record (cell x regions + region, value): value = luminance(L) cos /
// pdf of its direction if nothing blocked it, else 0 (the shadow stage sums them on the device,
// kernels/visibility_record.h, and absorb() takes the sums at each update). Per cell and region
// the values are summed in
// 64-bit fixed point, so the sums -- and the tables -- do not depend on the order records
// arrive in (threads, lanes, wave sizes, back ends): the tables depend on the seed alone (and, for
// the continuation guide below, on the paths' float radiance, which rounds differently on the two
// back ends past depth 1; tests/render/backends_test.cpp compares them statistically). Each
// value estimates, for the cell, the integral of L V cos over the region times the samples
// drawn; after passes 1, 2, 4, 8 ... L the host turns the sums into a CDF per cell:
//   P(R) = n / (n + n0) S(R) / sum S  +  n0 / (n + n0) M_R        (n records in the cell)
// -- shrinkage towards the map's own region masses M_R where a cell has few records, the map's
// distribution where it has none or saw no light -- and uploads the CDF of the mixture's region
// probabilities Q(R) = alpha M_R + (1 - alpha) P(R) (alpha: the map's defensive share) for the
// passes that follow.
// Passes L and later render with the last table and record nothing.
//
// The continuation guide (kernels/continuation_guide.h) learns the same way from records the
// schedule makes of every non-delta vertex's continuation during the learning passes: key cell x
// regions + the equal-area region of its direction, value luminance(L_in) / p of the direction,
// with L_in the radiance the rest of the path brought back along it (the path's radiance at its
// end less its radiance after the vertex, divided by the throughput after the vertex; MIS-weighted
// as the path counted it, so sky the light sample already covers weighs less). The sums take
// luminance(L_in) cos / p = pi p_b v (p_b = cos / pi, recovered from the record's density as for
// the secondary-source moments below): the guide follows the diffuse integrand, incident radiance
// x cosine, not the radiance alone (radiance alone left 13% / 4% / 17% more
// variance in window_room / skylight_room / the Cornell box: docs/history/results-journal.md). Per
// cell, P(R) = n / (n + n0) S(R) / sum S + n0 / (n + n0) / K (uniform where it knows little) and
// the guided share c = continuation_share x n / (n + n0), 0 where the cell saw no light come back.
//
// Portals (kernels/portal_guide.h): every unoccluded shadow-ray record also names the cell of the
// scene's box the ray left by; its value is summed there (the same fixed point), and the table
// over the box's cells is the CDF of those sums -- where the light the scene receives gets in.
// Which share b of a hash-grid cell's light samples goes to it is chosen per cell at each update
// among the candidates etk_portal_candidate: the one of least second moment of the light sample,
//   M(b) = sum over the cell's records since the last update of v^2 p_rec / p_b,
// v = g / p_rec the record's value, p_rec its density when drawn (the cell's last share) and
// p_b = (1 - b) p_vis + b p_portal from the two densities the record carries -- an importance-
// sampled estimate of the integral of g^2 / p_b. Open scenes, where light gets in everywhere,
// keep b = 0 (the portal table is then a poor density); a point that sees the sky through a
// window takes b > 0. The sums are fixed point, so the choice is order-independent too.
//
// Secondary sources (kernels/continuation_guide.h): every continuation record also names the
// cell of the box its ray leaves by (from its origin and direction); its value (the same
// luminance(L_in) cos / p, so a patch weighs by the light it sends to where it is seen from) is
// summed there, a second scene-wide table of the same layout: where the indirect light comes from
// (the sunlit patch on a floor). Each hash-grid cell's share q of its guided continuations drawn
// from it is chosen among the candidates etk_portal_candidate the same way, by the least second
// moment of the continuation over the cell's records since the last update:
//   M(q) = sum v^2 p_rec p_b^2 / p_q,   p_q = c' ((1 - q) p_guide + q p_spot) + (1 - c') p_b,
// v = luminance(L_in) / p_rec, the integrand f cos L_in being proportional to p_b luminance(L_in)
// at a diffuse vertex (p_b = cos / pi), p_b recovered from the record's density and the tables it
// was drawn with, c' = options.continuation_share (the share a well-learned cell will have); a
// share q > 0 is taken only where M(q) (1 - spot_cost) < M(0).
#pragma once
#include "kernels/portal_guide.h"
#include "kernels/visibility_guide.h"
#include "kernels/visibility_record.h"
#include "prepare/visibility_tables.h"
#include "util/float_span.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <vector>

namespace et {

// The candidate light-sample count n that minimises the efficiency model (m_cont + m_light / n)
// x (1 + cost n): the second moments, per vertex, of the continuation's estimate and of one
// light sample's (taking the light sample with probability n multiplies its second moment by
// 1 / n and its cost by n). A tie keeps the earlier candidate.
double light_sample_count(double m_light, double m_cont, double cost, const double* counts,
                          size_t n);

// Which of n candidate shares has the least second moment (moments[j], fixed point), a share
// j > 0 charged for what it costs: it must save `cost` of the moment of share 0 (the portal
// shares: 0; the secondary-source shares: spot_cost). A tie keeps the smaller share.
size_t least_moment_share(const uint64_t* moments, size_t n, double cost);

class VisibilityCache {
  public:
    // regions: guide_region_tables; scale: the map's power (values are kept relative to it);
    // box: the portal table's (guide_portal_box).
    VisibilityCache(const VisibilityOptions& options, const std::vector<float>& regions,
                    double scale, const std::array<float, 6>& box);
    // Shadow-ray records made on the host (thread-safe; a render's are summed on the device and
    // absorbed): cell x K + region, value, the portal cell the ray left the box by (-1: blocked)
    // and the densities p_vis, p_portal of its direction (2 n floats), and the values the rays
    // would have had unblocked (reaches; null: the values). The same function sums them as the
    // device's shadow stage (kernels/visibility_record.h), for the next tables().
    void add(const int* keys, const float* values, const int* exits, const float* parts, int n,
             const float* reaches = nullptr);
    // Continuation records made on the host (thread-safe; a render's are summed on the device,
    // as add()'s): cell x K + region (the direction's, etk_cguide_region: its guide density is
    // the region's), value luminance(L_in) / p, and per record 8 floats: the ray's origin, 0, its
    // direction and density p.
    void add_continuations(const int* keys, const float* values, const float* rays, int n);
    // The device's sums of records since the last call (WavefrontDevice::take_guide_sums),
    // added to the cache's and left zero (the device's next sums); between passes.
    void absorb(uint32_t* words, size_t count);
    // The cells' tables from everything recorded so far (guide_cells_size floats): the CDFs of Q,
    // then, with options.continuation, the continuation guide's CDFs and shares.
    // Each update also chooses the cells' portal shares and starts their measure afresh.
    // The cache's own buffer, rewritten in place by the next call.
    const std::vector<float>& tables();
    // The floats of tables() that the last call rewrote; the rest hold what they held (before
    // the first call the prior tables, guide_prior_cells, as DeviceScene::guide_cells does).
    const std::vector<FloatSpan>& changed() const { return changed_; }
    // Host memory of the sums, bytes.
    uint64_t bytes() const {
        return light_.bytes() + dir_.bytes() + portal_.size() * 8 + moments_.size() * 8 +
               shares_.size() * 4 + spot_.size() * 8 + spot_moments_.size() * 8 +
               spot_shares_.size() * 4 + guided_moments_.size() * 8 +
               (guided_shares_.size() + guided_records_.size()) * 4 + last_.size() * 4 +
               light_m2_.size() * 8 + cont_m2_.size() * 8;
    }
    // The cells of the last tables() that take fewer than one light sample, per count.
    const std::map<float, uint64_t>& fewer_light_samples() const { return fewer_; }
    // The slots of the last tables() that draw a share of their light samples from the portal
    // table (none while it holds nothing).
    uint64_t portal_cells() const {
        if (std::none_of(portal_.begin(), portal_.end(), [](uint64_t v) { return v > 0; }))
            return 0;
        return static_cast<uint64_t>(
            std::count_if(shares_.begin(), shares_.end(), [](float b) { return b > 0.0f; }));
    }
    uint64_t records() const { return light_.records; } // shadow-ray records
    // The share of the light sample's light that its shadow rays found unblocked, over every
    // record absorbed (each record's value is an unbiased estimate of its cell's integral of
    // L cos, with or without the visibility: the share does not depend on the density the
    // rays were drawn with); -1 where they carried none.
    double light_seen_share() const {
        return light_reach_ > 0.0 ? light_.total / light_reach_ : -1.0;
    }
    uint64_t continuation_records() const { return dir_.records; }
    // Whether the table should be rebuilt after learning pass `pass` (0-based): 1, 2, 4, ...
    static bool update_after(int pass, int learning_passes);

  private:
    // One kind of records, summed per slot and region.
    struct RegionSums {
        std::vector<uint64_t> sums;    // slots x K, fixed point
        std::vector<uint32_t> counts;  // records per slot
        std::vector<uint32_t> counted; // counts at the last update: the records since are the rest
        uint64_t records = 0;
        double total = 0.0; // the sum of sums, every slot and region (fixed point)
        uint64_t bytes() const {
            return sums.size() * sizeof(uint64_t) + (counts.size() + counted.size()) * 4;
        }
    };
    // Each slot with at least min_records records of `r` since the last update takes the
    // candidate share of least_moment_share; the moments start afresh and the records are
    // counted from here.
    void choose_shares(const double* candidates, size_t n, double cost, RegionSums& r,
                       std::vector<uint64_t>& moments, std::vector<float>& shares);
    // Each slot with at least min_records continuation records that brought light back, drawn
    // with a learned guide (after the first update), takes the guided share of least second
    // moment over all of them (the records of no light add nothing to any moment): unlike
    // the shares above, its moments are never reset, since the paths a guide misses are rare (the
    // sun's caustic through a glass or mirror-like statue) and one update's records seldom hold
    // them. Until then the slot keeps options.continuation_share.
    void choose_guided_shares();
    // The parameters the record functions take, and pending_ allocated.
    etk::EtkParams record_params();
    // One kind of records of cell s in the device's sums (kernels/visibility_record.h): its
    // count, second moment (a pair) and region sums (regions: the kind's pairs), added to r and
    // m2 and zeroed.
    void absorb_cell(RegionSums& r, uint64_t& m2, int s, uint32_t* regions, uint32_t* count,
                     uint32_t* moment);
    VisibilityOptions opt_;
    std::vector<float> mass_; // M_R
    std::array<float, 6> box_;
    std::vector<uint64_t> portal_; // per portal cell, fixed point
    // Per slot and candidate share, the light sample's second moment (fixed point).
    std::vector<uint64_t> moments_;
    std::vector<float> shares_; // the portal shares of the last update, per slot
    // The secondary-source table's sums and, per slot, moments and shares.
    std::vector<uint64_t> spot_, spot_moments_;
    std::vector<float> spot_shares_;
    // Per slot, the continuation's second moment for each of etk_guided_candidate over every
    // record so far, and the chosen guided share.
    std::vector<uint64_t> guided_moments_;
    std::vector<float> guided_shares_;
    std::vector<uint32_t> guided_records_; // the records summed in guided_moments_, per slot
    bool guide_learned_ = false;           // tables() has run: the records' guide is a learned one
    // Per slot, the second moments of one light sample's and one continuation's estimate (fixed
    // point, in the common unit of light_sample_count).
    std::vector<uint64_t> light_m2_, cont_m2_;
    std::map<float, uint64_t> fewer_;
    // The tables of the last update (tables()): those the passes since were drawn with.
    std::vector<float> last_;
    std::vector<FloatSpan> changed_; // the spans of last_ the last tables() rewrote
    std::vector<char> fresh_;        // per slot: records since the last tables()
    float inv_power_;                // 1 / the map's power
    std::array<double, ETK_PORTAL_CANDIDATES> portal_candidates_; // etk_portal_candidate
    std::array<double, ETK_GUIDED_CANDIDATES> guided_candidates_; // etk_guided_candidate
    std::vector<uint32_t> pending_; // add()'s sums (visibility_record.h's layout) until tables()
    RegionSums light_, dir_;        // the light sample's (shadow rays), the continuation guide's
    double light_reach_ = 0.0; // the light records' values had nothing blocked them (fixed point)
    mutable std::mutex mutex_;
};

} // namespace et
