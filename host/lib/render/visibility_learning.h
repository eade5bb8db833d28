// The visibility strategy's learning (kernels/visibility_guide.h, portal_guide.h,
// continuation_guide.h) as a learning policy: during its learning passes the stages sum every
// shadow ray's and every guided vertex's continuation's record on the device
// (kernels/visibility_record.h); after passes 1, 2, 4 ... L the visibility cache
// (visibility_cache.h) takes the sums and the cells' tables are rebuilt and uploaded; after the
// verdict's passes of the tables, as many passes of the fallback (the paper's MIS for the
// visibility strategy, compensated for auto: VisibilityOptions::fallback) measure it
// (guide_verdict.h), and the cheaper one per error renders the rest of the image. For auto a
// screen comes first (VisibilityOptions::screen): where the first updates' shadow rays found
// nearly all the light they carried unblocked (an open sky), the tables go, saving the 20 passes
// of them a measured verdict costs there: past depth 1 the verdict is the fallback's at once; at
// depth 1 the binned light samples (VisibilityOptions::alternative) render on, and the verdict
// weighs their passes against the fallback's. Where they found very little of it unblocked (a
// room lit through openings), the tables stay at once, unmeasured. How long the
// learning goes on is decided at each update from the samples the render will take (plan): it
// ends at an update whose successor no planned sample would use (a learning pass costs about
// 1.25 steady ones, and a 64-sample render at 128 x 96 paid it on passes 33-64 for tables after
// pass 64 that nothing rendered with), and goes on past L in a render whose time limit leaves
// room enough (VisibilityOptions::long_render).
#pragma once
#include "render/guide_verdict.h"
#include "render/learning_policy.h"
#include "render/visibility_cache.h"

#include <map>
#include <memory>
#include <vector>

namespace et {

class VisibilityLearning : public LearningPolicy {
  public:
    VisibilityLearning(const DeviceScene& scene, bool batches);
    int learning_passes() const override;
    void configure(etk::EtkParams& p, uint32_t sample_index, bool learn) const override;
    bool reads_film(uint32_t sample_index) const override;
    void plan(const LearningPlan& plan) override { plan_ = plan; }
    bool after_pass(int pass, uint32_t sample_index, const Film* film, double seconds,
                    WavefrontDevice& device, const MeasuringPass& measure) override;
    nlohmann::json stats() const override;

  private:
    // The verdict's passes of the fallback use sample indices of their own, never kept: they
    // measure it without adding its variance to the image.
    static constexpr uint32_t kVerdictFallbackBase = 0x80000000u;
    // What pass `sample_index` renders: Strategy::visibility for the tables, or a verdict's
    // measuring pass's technique, or the technique of the last switch at or before it.
    Strategy technique_of(uint32_t sample_index) const;
    // The technique the verdict's kept passes render: the tables, or the screen's alternative.
    Strategy kept_technique() const;
    bool learns_tables(uint32_t sample_index) const;
    int verdict_start() const; // the first of the verdict's kept passes
    // Where the learning ends, decided at the update after `done` learning passes: there, or at
    // the next update, or at L.
    int learning_end_at(int done) const;
    // The tables after learning pass `pass`, where the schedule rebuilds them, and where the
    // learning ends (learning_end_at).
    void update_tables(int pass, WavefrontDevice& device);
    // The verdict's screen (VisibilityOptions::screen, alternative_share, tables_share), at the
    // update after learning pass `pass`: it may switch from the next pass to the fallback (past
    // depth 1) or to the alternative, which the verdict then weighs (depth 1), or keep the
    // tables without a verdict; otherwise the verdict is measured.
    void screen(int pass);
    // Passes `from` and later render `technique` (the learning of the tables ends).
    void switch_to(int from, Strategy technique);
    // The device's record sums since the last call, into the cache (and the figures).
    void take_records(WavefrontDevice& device);
    // The verdict's passes of the fallback, then the choice. False where one was abandoned.
    bool give_verdict(const MeasuringPass& measure);

    const DeviceScene& scene_;
    VisibilityOptions options_;
    bool batches_;       // the sample_lights stage, where the fallback's technique allows it
    bool alternative_;   // at depth 1 the screen may drop the tables for options_.alternative
    bool ready_ = false; // the cells' tables hold something learned
    // What the passes render past the tables: from each switch's pass on, its technique, until
    // the next. A verdict against the tables switches at the end of its passes; the screen at the
    // next pass (past depth 1 to the fallback, at depth 1 to the alternative, which its verdict
    // then measures against the fallback and may switch from).
    struct Switch {
        int from;
        Strategy technique;
    };
    std::vector<Switch> switches_;
    bool decided_ = false;            // the verdict is given: no more passes to measure
    bool measured_ = false;           // ... by measuring (a resume renders its passes again)
    bool alternative_kept_ = false;   // the screen kept the alternative for the verdict to weigh
    bool screened_ = false;           // the screen was applied (at most once)
    double screen_share_ = -1;        // the light share the screen saw (-1: none)
    const char* verdict_by_ = "none"; // how the verdict was given: "screen" or "measure"
    // Passes 0 .. learn_until_ - 1 record: options_.learning_passes, fewer or more as the plan
    // decides at the updates from the render's plan.
    int learn_until_ = 0;
    LearningPlan plan_;
    std::unique_ptr<VisibilityCache> cache_;
    std::unique_ptr<GuideVerdict> verdict_;
    // Figures (stats()).
    double learning_seconds_ = 0, update_seconds_ = 0, verdict_seconds_ = 0;
    int learned_passes_ = 0; // learning passes rendered so far (learn_until_: where they end)
    uint64_t records_ = 0, continuation_records_ = 0, host_bytes_ = 0, device_bytes_ = 0;
    double verdict_fallback_error_ = 0, verdict_kept_error_ = 0, verdict_log_ratio_se_ = 0;
    std::map<float, uint64_t> light_counts_;
    uint64_t portal_cells_ = 0; // of the last update's tables (VisibilityCache::portal_cells)
};

} // namespace et
