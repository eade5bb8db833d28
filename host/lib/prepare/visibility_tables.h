// The visibility strategy's tables as the device gets them before anything is learned
// (kernels/visibility_guide.h, continuation_guide.h, portal_guide.h): the options that size and
// tune them, the map's region tables, the cells' prior tables and the portal box. Preparation
// builds them once per scene (prepare/device_scene.cpp); the learning between passes
// (render/visibility_cache.h) rewrites the cells' tables with the same writers.
#pragma once
#include "kernels/portal_guide.h"
#include "load/render_settings.h"
#include "kernels/visibility_guide.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace et {

struct VisibilityOptions {
    // Hash-grid cells (a power of two): 2^13 x 2 x 514 floats = 32 MiB of tables on the device
    // (window_room's variance 0.00887 with 2^13, 0.00875 with 2^14 at twice the memory, 0.00915
    // with 2^12: docs/history/results-journal.md), and 68 MB of record sums. Preparation caps it
    // for the film (guide_slots) and for the cells the scene's grid has (guide_grid_slots).
    int slots = 1 << 13;
    int resolution = 8; // cells along the scene's longest side (few records per cell
                        // otherwise: measured in docs/history/results-journal.md)
    // The map's defensive share of every light sample (light samples weigh at most 1 / alpha
    // times the map's own). With 16 x 32 regions 0.1 (against 0.25) leaves 7-8% less
    // variance in window_room (320 x 240 and 160 x 120), skylight_room and the Cornell box, 4% on
    // bunny_grace, the same at 80 x 60 (docs/history/results-journal.md).
    float alpha = 0.1f;
    // Samples 0 .. L-1 record shadow rays and continuations, L = learning_passes; preparation
    // sets it for the film (guide_learning_passes): as many passes as learn from about
    // learning_paths camera paths, within [min_learning_passes, max_learning_passes]. The tables
    // saturate: at 320 x 240 (76,800 paths a pass) 16, 32 and 64 passes leave window_room's
    // variance within 3% while each learning pass costs ~1.3 steady ones; at 80 x 60, 16 passes
    // gave 1.78x MIS's efficiency and 64 2.17x (docs/history/results-journal.md).
    int learning_passes = 64;
    int min_learning_passes = 16, max_learning_passes = 64;
    double learning_paths = 2.0e6;
    // A render whose time limit leaves room (LearningPlan not fixed) learns on past L, from the
    // update after U passes to the one after 2U, while the estimate holds at least long_render x U
    // samples (so at most about half of it learns), up to planned_learning_passes (the measured
    // range). A fixed count never does: a resume to more samples would learn where the first run
    // had stopped, and render its samples with other tables. The tables are
    // record-starved at 128 x 96 in rooms lit by a sun through small openings: at depth 1 (4 s,
    // ~950 samples) learning to 256 passes rather than 64 measured 1.4-1.7x the efficiency on
    // three such rooms, the same on the others; at depth 5 (~170 samples) factor 4 stops at 64, 2
    // learnt to 128 and lost 6-15% (docs/history/results-journal.md, "Learning as long as the
    // render").
    double long_render = 4.0;
    int planned_learning_passes = 256;
    // n0: records a cell needs before its own sums weigh half (its light table's and its guided
    // continuations' share). At 128 x 96 (12,288 paths a pass) a cell's records are few and
    // noisy: 512 against 32 left 10% less equal-spp error in geometric mean on both halves of
    // the held-out set at 32 spp (lower on 14 of 16 scenes; 8 was worse on all eight tuned on),
    // and 3-17% less on three of four at 128 spp (docs/history/results-journal.md).
    double prior = 512.0;
    // Records a cell needs of a kind before it makes its own choices below (its portal share, its
    // secondary-source share, its light-sample count); until then it keeps the default.
    int min_records = 64;
    bool continuation = true; // guide diffuse vertices' continuations as well
    // The guided share of a well-learned cell's continuations (0.3 / 0.5 / 0.7 measured:
    // docs/history/results-journal.md), until the cell chooses its own among guided_shares.
    double continuation_share = 0.5;
    // Each cell's guided share c, once it has min_records continuation records: the candidate
    // (etk_guided_candidate) whose continuation has the least second moment on all its records.
    // The secondary-source table's share of a cell's guided continuations: chosen among the
    // portal share's candidates (etk_portal_candidate) as the portal share is (0 until the cell has
    // min_records continuation records), except that a share q > 0 must lower the second moment by
    // spot_cost of it, the extra time its density costs at every guided vertex of the cell
    // (equal-spp relative variance, 320 x 240, 128 spp: skylight_room 0.0346 -> 0.0218 / 0.0239 /
    // 0.0322 with a cost of 0 / 0.15 / 0.3, window_room 0.0187 -> 0.0177 / 0.0185 / 0.0186, while a
    // cost of 0 took ~15% more time per sample: docs/history/results-journal.md).
    double spot_cost = 0.15;
    // Each cell's expected light samples n (kernels/visibility_guide.h, etk_guide_light_count):
    // the candidate of light_sample_count on the second moments of the cell's light samples and
    // continuations, a light sample costing light_cost of the rest of a vertex and its path (1
    // until the cell has min_records records of either kind). Measured, 320 x 240, 128
    // spp, two seeds, two alternations: relative variance x time, window_room / skylight_room,
    // 1 everywhere 0.53 / 0.71; cost 0.5: 0.45 / 0.66; 1: 0.50 / 0.66; 2: 0.50 / 0.65 (a light
    // sample is costly here: the guided sample, its densities, the shadow ray; 30% fewer shadow
    // rays took 20-25% of the time off).
    std::array<double, 4> light_counts{{1.0, 0.5, 0.25, 0.125}};
    double light_cost = 0.5;
    // The verdict (render/guide_verdict.h): the verdict_passes passes from pass verdict_after
    // on (the tables learned from that many passes, or from all L where L is fewer; the passes
    // still learn where they are learning passes) and as many passes of MIS, each in two blocks;
    // the tables stay -- and learn on to L -- if MIS's error is at least verdict_cost times
    // theirs, otherwise every later pass renders MIS and the learning ends there (a render under
    // the open sky saves the learning passes' cost, 2-2.3x a MIS pass's on the efficiency suite).
    // verdict_cost is the tables' time per sample over MIS's after learning, verdict_cost_guided
    // the same where the continuation is guided too (depth > 1): measured (native, the efficiency
    // suite, samples 64 .. 447 less 64 .. 191, so no learning is in it) 1.19-1.26 at
    // depth 1 and 1.29-1.43 at depth 5, 1.61 in window_room (docs/history/results-journal.md, "The
    // visibility strategy's verdict" and "The tables under the open sky"). 0 passes: no verdict,
    // the tables throughout.
    int verdict_passes = 8;
    int verdict_after = 16;
    // The fallback's measuring passes render every verdict_stride-th pixel only, and the verdict
    // compares the two on those pixels: passes that are not kept cost 1 / verdict_stride of a pass.
    int verdict_stride = 1;
    double verdict_cost = 1.25;
    double verdict_cost_guided = 1.4;
    // The verdict's screen (VisibilityLearning): at the first update before the verdict's passes
    // whose records number at least screen_records, the share of the light they carried that the
    // shadow rays found unblocked. Where continuations are guided (depth > 1), at a share of at
    // least 1 / the verdict's cost, the verdict is for the fallback at once, without its
    // measuring passes. Where the alternative serves (depth 1), at a share of at least
    // alternative_share, the alternative renders from the next pass on instead of the tables,
    // and the verdict weighs its passes (from a multiple of verdict_passes) against the
    // fallback's, at alternative_cost. At any depth, at a share below tables_share (but above
    // 0), the verdict is for the tables at once. Otherwise the tables' verdict is measured as
    // above.
    bool screen = false;
    int screen_records = 4096;
    // The technique the screen puts in the tables' place at depth 1, and its time per sample
    // over the fallback's. Only the cosine strategy's binned technique serves (its tables sit
    // after the learned ones in guide_cells: EtkParams::bin_cell_base); Strategy::mis: none.
    Strategy alternative = Strategy::mis;
    double alternative_cost = 1.0;
    // The binned samples know nothing of what blocks the map: where most of its light is
    // blocked (rooms lit through openings: shares 0.004-0.085; open scenes 0.64-0.99) the tables
    // stay in the verdict.
    double alternative_share = 0.5;
    // Where the shadow rays found so little of the light unblocked, the tables (which learn where
    // it comes through) beat compensated by 2-12x in every room measured (shares 0.001-0.085),
    // and the verdict, measuring tables learnt from 4-19 passes, can miss it: a held-out room at
    // share 0.001 chose compensated in two seeds of three (1.12x and 0.99x its error against a
    // cost of 1.25), 3.9x `mis` where the tables took 12.4x. 0: never.
    double tables_share = 0.0;
    // What the verdict weighs the tables against, and what renders after a verdict against them:
    // the paper's MIS for the visibility strategy, compensated for auto (auto_visibility_options).
    Strategy fallback = Strategy::mis;
};

// The auto strategy's options: the visibility strategy's tables, measured early against
// compensated, the default's estimator without learning, so that a scene where learning does
// not pay stops paying for it after a few passes.
VisibilityOptions auto_visibility_options();

// The cost the verdict weighs the tables' error by: verdict_cost_guided where the render guides
// its continuations as well (EtkParams::guide_continuation), verdict_cost otherwise.
inline double verdict_cost_for(const VisibilityOptions& o, bool continuation_guided) {
    return continuation_guided ? o.verdict_cost_guided : o.verdict_cost;
}

// Whether the screen may put options.alternative in the tables' place: only where continuations
// are not guided (depth 1), and only the binned technique (the cosine strategy's).
inline bool screen_keeps_alternative(const VisibilityOptions& o, bool continuation_guided) {
    return !continuation_guided && o.screen && o.verdict_passes > 0 &&
           o.alternative == Strategy::cosine;
}

// The map's region masses and row tables from its 2D distribution (piecewise_constant.h layout).
std::vector<float> guide_region_tables(const std::vector<float>& dist, int w, int h);

// The map's power (luminance over the sphere), the unit the learning's fixed point is relative to.
double guide_map_power(const std::vector<float>& rgb, int w, int h);
// The records' unit (EtkParams::guide_inv_power): 1 / the map's power, 1 for a black map.
float guide_inv_power(double power);

// The learning passes of a film of `pixels` pixels: the first of min_learning_passes, twice that,
// four times ... whose passes trace at least options.learning_paths camera paths, at most
// max_learning_passes (320 x 240: 32; 160 x 120 and smaller: 64; 640 x 480 and larger: 16).
int guide_learning_passes(const VisibilityOptions& options, int64_t pixels);

// The hash grid's slots for a film of `pixels` pixels: options.slots, but no more than the
// smallest power of two >= pixels (at least 64). A learning pass traces one camera path per
// pixel, so a small film's cells hold few records whatever their number, while every slot costs
// its tables and sums (and a device's time to write and read them). Films of 4,097 pixels and up
// (64 x 64) keep every slot.
int guide_slots(const VisibilityOptions& options, int64_t pixels);

// The slots of a grid over a box of extent `extent` with cells of 1 / inv_cell: `slots`, but no
// more than the smallest power of two >= twice the keys the grid can make (its cells x
// ETK_GUIDE_NORMAL_BUCKETS; at least 64). A room of 6 x 3 x 6 m keeps all 8,192 at 8 cells along
// its longest side, a statue on a 40 m ground (486 keys) has 1,024: a table no key reaches is
// memory, preparation and cache lines for nothing. The held-out rooms keep 4,096 and their open
// scenes 1,024: the device's tables and sums 102 -> 51 / 13 MB, a 1-spp render's setup 0.17 ->
// 0.05 s under the open sky, efficiency within the seeds' noise (at 4 s against `mis`: tune
// half 2.09 -> 2.15, report half 2.23 -> 2.25, a fresh set 2.30 -> 2.32; twice the keys rather
// than once for fewer collisions, the two alike on the tune half;
// docs/history/results-journal.md, "Slots for the grid's keys").
int guide_grid_slots(int slots, const float extent[3], float inv_cell);

// Floats of the cells' tables (EtkScene.guide_cells): the light sample's, then the continuation
// guide's if it is on (kernels/visibility_guide.h), the portal table, and with the continuation
// guide the secondary-source table (kernels/continuation_guide.h).
size_t guide_cells_size(int slots, bool continuation);

// The portal table's box: the scene's bounds lo, hi enlarged so that every surface point lies
// strictly inside (a ray from it has a positive distance to the face it leaves by).
std::array<float, 6> guide_portal_box(const float lo[3], const float hi[3]);

// Every cell's tables before anything is learned: the map's region masses (the map's own
// distribution) and, with the continuation guide, uniform regions with a share of 0.
// The portal table follows, over `box` (guide_portal_box), with a share of 0, and with the
// continuation guide the secondary-source table, off.
std::vector<float> guide_prior_cells(const std::vector<float>& regions, int slots,
                                     bool continuation, const std::array<float, 6>& box);

// A CDF over the ETK_GUIDE_REGIONS regions from probabilities (summing to about 1): cdf[0] = 0,
// cdf[K] = 1 (uniform where they are all 0).
void write_guide_cdf(const std::vector<double>& prob, float* cdf);

// A portal-layout table (kernels/portal_guide.h): box, whether it is on, the CDF over the box's
// cells from sums (uniform if all are zero: then it is off) and its guide, the slots' shares.
void write_portal_table(const std::array<float, 6>& box, const std::vector<float>& shares,
                        const std::vector<double>& sums, float* out);

} // namespace et
