// The visibility strategy's learned tables (kernels/visibility_guide.h), on the host: the map's
// region tables (built once from its distribution), the hash grid's placement over the scene, and
// the learning between passes.
//
// Learning: during the learning passes (samples 0 .. L-1, L = 64) every shadow ray of the
// visibility strategy leaves a record (cell x regions + region, value): value = luminance(L) cos /
// pdf of its direction if nothing blocked it, else 0 (the shadow stage writes them in queue order;
// the schedule hands each bounce's records here). Per cell and region the values are summed in
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
// as the path counted it, so sky the light sample already covers weighs less). Radiance, not
// radiance x cos: the mixture's BSDF half brings the cosine. Per cell,
// P(R) = n / (n + n0) S(R) / sum S + n0 / (n + n0) / K (uniform where it knows little) and the
// guided share c = continuation_share x n / (n + n0), 0 where the cell saw no light come back.
#pragma once
#include "kernels/visibility_guide.h"

#include <cstdint>
#include <mutex>
#include <vector>

namespace et {

struct VisibilityOptions {
    int slots = 1 << 14; // hash-grid cells (a power of two)
    int resolution = 8;  // cells along the scene's longest side (few records per cell
                         // otherwise: measured in docs/results.md, issue 11)
    float alpha = 0.25f; // the map's defensive share of every light sample
    // Samples 0 .. 63 record shadow rays and continuations (16: 1.78x -> 64: 2.17x MIS's
    // efficiency on the interiors; docs/results.md, issue 11).
    int learning_passes = 64;
    double prior = 32.0;      // n0: records a cell needs before its own sums weigh half
    bool continuation = true; // guide diffuse vertices' continuations as well
    // The guided share of a well-learned cell's continuations (0.3 / 0.5 / 0.7 measured:
    // docs/results.md, issue 11).
    double continuation_share = 0.5;
};

// The map's region masses and row tables from its 2D distribution (piecewise_constant.h layout).
std::vector<float> guide_region_tables(const std::vector<float>& dist, int w, int h);

// The map's power (luminance over the sphere), the unit the learning's fixed point is relative to.
double guide_map_power(const std::vector<float>& rgb, int w, int h);

// Floats of the cells' tables (EtkScene.guide_cells): the light sample's, then the continuation
// guide's if it is on (kernels/visibility_guide.h).
size_t guide_cells_size(int slots, bool continuation);

// Every cell's tables before anything is learned: the map's region masses (the map's own
// distribution) and, with the continuation guide, uniform regions with a share of 0.
std::vector<float> guide_prior_cells(const std::vector<float>& regions, int slots,
                                     bool continuation);

class VisibilityCache {
  public:
    // regions: guide_region_tables; scale: the map's power (values are kept relative to it).
    VisibilityCache(const VisibilityOptions& options, const std::vector<float>& regions,
                    double scale);
    // One bounce's shadow-ray records (thread-safe).
    void add(const int* keys, const float* values, int n);
    // One wave's continuation records (thread-safe).
    void add_continuations(const int* keys, const float* values, int n);
    // The cells' tables from everything recorded so far (guide_cells_size floats): the CDFs of Q,
    // then, with options.continuation, the continuation guide's CDFs and shares.
    std::vector<float> tables() const;
    // Host memory of the sums, bytes.
    uint64_t bytes() const { return light_.bytes() + dir_.bytes(); }
    uint64_t records() const { return light_.records; } // shadow-ray records
    uint64_t continuation_records() const { return dir_.records; }
    // Whether the table should be rebuilt after learning pass `pass` (0-based): 1, 2, 4, ...
    static bool update_after(int pass, int learning_passes);

  private:
    // One kind of records, summed per slot and region.
    struct RegionSums {
        std::vector<uint64_t> sums;   // slots x K, fixed point
        std::vector<uint32_t> counts; // records per slot
        uint64_t records = 0;
        uint64_t bytes() const { return sums.size() * sizeof(uint64_t) + counts.size() * 4; }
    };
    void add_to(RegionSums& to, const int* keys, const float* values, int n);
    VisibilityOptions opt_;
    std::vector<float> mass_; // M_R
    double inv_scale_;
    RegionSums light_, dir_; // the light sample's (shadow rays), the continuation guide's
    mutable std::mutex mutex_;
};

} // namespace et
