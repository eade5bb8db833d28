// The visibility strategy's learning (kernels/visibility_guide.h, portal_guide.h,
// continuation_guide.h) as a learning policy: during its learning passes the stages sum every
// shadow ray's and every guided vertex's continuation's record on the device
// (kernels/visibility_record.h); after passes 1, 2, 4 ... L the visibility cache
// (visibility_cache.h) takes the sums and the cells' tables are rebuilt and uploaded; after the
// verdict's passes of the tables, as many passes of the fallback (the paper's MIS for the
// visibility strategy, compensated for auto: VisibilityOptions::fallback) measure it
// (guide_verdict.h), and the cheaper one per error renders the rest of the image. For auto a
// screen comes first (VisibilityOptions::screen): where the first updates' shadow rays found
// nearly all the light they carried unblocked (an open sky), the verdict is the fallback's at
// once, saving the 20 passes of the tables a measured verdict costs there. How long the
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
    // The verdict's passes of the fallback, and of the alternative, use sample indices of their
    // own, never kept: they measure it without adding its variance to the image.
    static constexpr uint32_t kVerdictFallbackBase = 0x80000000u;
    static constexpr uint32_t kVerdictAlternativeBase = 0xc0000000u;
    // Whether pass `sample_index` renders a technique other than the tables: a verdict's
    // measuring pass, or any pass after a verdict for the fallback (or the alternative).
    bool fallback_pass(uint32_t sample_index) const;
    // Which, where fallback_pass.
    Strategy fallback_technique(uint32_t sample_index) const;
    bool learns_tables(uint32_t sample_index) const;
    int verdict_start() const; // the first of the verdict's passes of the tables
    // Where the learning ends, decided at the update after `done` learning passes: there, or at
    // the next update, or at L.
    int learning_end_at(int done) const;
    // The tables after learning pass `pass`, where the schedule rebuilds them, and where the
    // learning ends (learning_end_at).
    void update_tables(int pass, WavefrontDevice& device);
    // The verdict's screen (VisibilityOptions::screen, alternative_share), at the update after
    // learning pass `pass`: true where it chose the fallback from the next pass on; it also
    // decides whether the alternative is measured.
    bool screen_out(int pass);
    // A verdict for the fallback: passes `from` and later render it, and the learning ends.
    void drop_tables(int from);
    // The device's record sums since the last call, into the cache (and the figures).
    void take_records(WavefrontDevice& device);
    // The verdict's passes of the fallback, then the choice. False where one was abandoned.
    bool give_verdict(const MeasuringPass& measure);

    const DeviceScene& scene_;
    VisibilityOptions options_;
    bool batches_;             // the sample_lights stage, where the fallback's technique allows it
    bool alternative_;         // the verdict measures options_.alternative too
    Strategy fallback_;        // what renders after a verdict against the tables
    bool ready_ = false;       // the cells' tables hold something learned
    bool dropped_ = false;     // the verdict chose the fallback: the passes after it render it
    int fallback_from_ = 0;    // where dropped_: the first pass of the fallback
    bool screened_ = false;    // the screen was applied (at most once)
    double screen_share_ = -1; // the light share the screen saw (-1: none)
    const char* verdict_by_ = "none"; // how the verdict was given: "screen" or "measure"
    // Passes 0 .. learn_until_ - 1 record: options_.learning_passes, fewer or more as the plan
    // decides at the updates from the render's plan.
    int learn_until_ = 0;
    LearningPlan plan_;
    std::unique_ptr<VisibilityCache> cache_;
    std::unique_ptr<GuideVerdict> verdict_;
    // Figures (stats()).
    double learning_seconds_ = 0, update_seconds_ = 0, verdict_seconds_ = 0;
    int chosen_ = -1; // the verdict: 1 tables, 0 fallback, -1 not yet
    uint64_t records_ = 0, continuation_records_ = 0, host_bytes_ = 0, device_bytes_ = 0;
    double verdict_fallback_error_ = 0, verdict_tables_error_ = 0, verdict_alternative_error_ = 0;
    std::map<float, uint64_t> light_counts_;
};

} // namespace et
