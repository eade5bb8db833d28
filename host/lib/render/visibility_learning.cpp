#include "render/visibility_learning.h"

#include "prepare/device_scene.h"
#include "prepare/technique.h"
#include "render/film.h"
#include "util/error.h"
#include "util/timer.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace et {

VisibilityLearning::VisibilityLearning(const DeviceScene& scene, bool batches)
    : scene_(scene), options_(scene.guide_options), batches_(batches),
      alternative_(screen_keeps_alternative(options_, scene.params.guide_continuation != 0)),
      learn_until_(options_.learning_passes) {
    options_.continuation = scene.params.guide_continuation != 0;
    std::array<float, 6> box;
    const float* table = scene.guide_cells.data() +
                         etk::etk_portal_offset(options_.slots, options_.continuation ? 1 : 0);
    std::copy(table, table + 6, box.begin());
    cache_ = std::make_unique<VisibilityCache>(options_, scene.guide_regions, scene.guide_map_power,
                                               box);
    host_bytes_ = cache_->bytes();
    device_bytes_ = (scene.guide_cells.size() + scene.guide_regions.size()) * sizeof(float) +
                    scene.guide_sum_words() * sizeof(uint32_t);
}

int VisibilityLearning::verdict_start() const {
    const int start = std::min(options_.learning_passes, options_.verdict_after);
    // The alternative's kept passes from a multiple of verdict_passes: its blocks then stand in
    // the Sobol' sequence as the fallback's measuring passes do (kVerdictFallbackBase + 0 ..
    // passes - 1, one aligned run of 16). The two blocks' difference depends on that: on passes 8
    // .. 23 the binned samples' error measured 1.10-1.40x what it did on their measuring indices
    // (two open scenes, six seeds each) and turned most of those verdicts against them; on 16 ..
    // 31, 0.85-1.16x (three seeds each).
    if (alternative_kept_) {
        const int block = std::max(1, options_.verdict_passes);
        return (start + block - 1) / block * block;
    }
    return start;
}

int VisibilityLearning::learning_passes() const {
    // The passes the tables learn from and the verdict's; a verdict for another technique ends
    // the learning where that technique begins.
    if (decided_ && !switches_.empty())
        return switches_.back().from;
    const bool verdict = options_.verdict_passes > 0 && (!decided_ || measured_);
    return std::max(learn_until_, verdict ? verdict_start() + options_.verdict_passes : 0);
}

Strategy VisibilityLearning::technique_of(uint32_t sample_index) const {
    if (sample_index >= kVerdictFallbackBase)
        return options_.fallback;
    Strategy s = Strategy::visibility;
    for (const Switch& w : switches_)
        if (sample_index >= uint32_t(w.from))
            s = w.technique;
    return s;
}

Strategy VisibilityLearning::kept_technique() const {
    return technique_of(uint32_t(verdict_start()));
}

bool VisibilityLearning::learns_tables(uint32_t sample_index) const {
    return technique_of(sample_index) == Strategy::visibility &&
           sample_index < uint32_t(learn_until_);
}

// Updates come after passes 1, 2, 4 ... (and the last learning pass), and the learning ends only
// at one: a sample renders with the tables of the last update at or before it, so a plan that
// ends the learning before a sample's tables would change changes no sample of the film below it
// (farm tasks, given the whole render's plan, learn alike; a render resumed to more samples
// learns more and renders the samples it had with the same tables). Only an estimate (a time
// limit) takes the learning past L: with a fixed count, a resume to more samples would learn on
// where the first run had stopped, and render its samples with other tables.
int VisibilityLearning::learning_end_at(int done) const {
    const int64_t planned = plan_.samples;
    if (done < options_.learning_passes) // the film's learning, unless no planned sample needs it
        return planned > 0 && planned <= 2 * int64_t(done) ? done : options_.learning_passes;
    const bool long_render = !plan_.fixed && planned > 0 &&
                             done < options_.planned_learning_passes &&
                             double(planned) >= options_.long_render * double(done);
    return long_render ? 2 * done : done;
}

void VisibilityLearning::configure(etk::EtkParams& p, uint32_t sample_index, bool learn) const {
    p.guide_ready = ready_ ? 1 : 0;
    // The verdict's measuring passes and, after a verdict for it, every pass: the fallback
    // estimator (or the alternative), with the strategy's MIS heuristic and GGX sampling. The
    // binned technique's tables are prepared, never learned: ready from the start.
    const Strategy s = technique_of(sample_index);
    if (s != Strategy::visibility) {
        set_technique(p, s);
        p.light_batch = batches_ && technique_batches_light_samples(p) ? 1 : 0;
        p.guide_ready = p.light_first == ETK_LIGHT_BINNED ? 1 : 0;
    }
    p.guide_learn = learn && learns_tables(sample_index) ? 1 : 0;
    p.guide_continuation_share = static_cast<float>(options_.continuation_share);
}

void VisibilityLearning::update_tables(int pass, WavefrontDevice& device) {
    // Rebuilt after passes 1, 2, 4, ... and the last learning pass; where the learning ends is
    // decided there.
    if (!VisibilityCache::update_after(pass, learn_until_))
        return;
    const Timer t;
    take_records(device);
    screen(pass);
    if (!switches_.empty()) { // the screen dropped the tables: nothing more to upload
        update_seconds_ += t.seconds();
        return;
    }
    const std::vector<float>& tables = cache_->tables();
    device.upload_guide(tables, cache_->changed());
    ready_ = true;
    light_counts_ = cache_->fewer_light_samples();
    portal_cells_ = cache_->portal_cells();
    learn_until_ = learning_end_at(pass + 1);
    update_seconds_ += t.seconds();
}

void VisibilityLearning::screen(int pass) {
    // Once, at the first update before the verdict's passes (which fix what it measures) whose
    // records suffice: the share of their light the shadow rays found unblocked decides what the
    // verdict weighs: at depth 1 (where the alternative serves), at a share of at least
    // alternative_share, the alternative against the fallback, without the tables; past depth 1,
    // at a share of at least 1 / the tables' cost, the fallback at once; at any depth, below
    // tables_share (but some light found), the tables at once. Otherwise, or without the
    // records, the tables against the fallback.
    if (!options_.screen || options_.verdict_passes <= 0 || screened_ || decided_ ||
        pass + 1 > verdict_start() ||
        cache_->records() < static_cast<uint64_t>(options_.screen_records))
        return;
    screened_ = true;
    screen_share_ = cache_->light_seen_share();
    if (screen_share_ < 0.0)
        return; // no light carried: no evidence
    if (alternative_ && screen_share_ >= options_.alternative_share) {
        switch_to(pass + 1, options_.alternative); // its verdict is still to be measured
        alternative_kept_ = true;
    } else if (options_.continuation && screen_share_ * verdict_cost_for(options_, true) >= 1.0) {
        switch_to(pass + 1, options_.fallback);
        decided_ = true;
    } else if (screen_share_ > 0.0 && screen_share_ < options_.tables_share) {
        decided_ = true; // the tables, unmeasured
    } else {
        return;
    }
    verdict_by_ = "screen";
}

void VisibilityLearning::switch_to(int from, Strategy technique) {
    switches_.push_back({from, technique});
    learn_until_ = std::min(learn_until_, from);
}

void VisibilityLearning::take_records(WavefrontDevice& device) {
    device.absorb_guide_sums([this](uint32_t* sums, size_t n) { cache_->absorb(sums, n); });
    records_ = cache_->records();
    continuation_records_ = cache_->continuation_records();
}

// The verdict's kept passes are measured on their films.
bool VisibilityLearning::reads_film(uint32_t sample_index) const {
    if (decided_)
        return false;
    const int64_t verdict_pass = int64_t(sample_index) - verdict_start();
    return verdict_pass >= 0 && verdict_pass < options_.verdict_passes;
}

bool VisibilityLearning::after_pass(int pass, uint32_t sample_index, const Film* film,
                                    double seconds, WavefrontDevice& device,
                                    const MeasuringPass& measure) {
    if (learns_tables(sample_index) && cache_) {
        const Timer t;
        update_tables(pass, device);
        learning_seconds_ += seconds + t.seconds();
        ++learned_passes_;
        if (pass + 1 >= learn_until_)
            cache_.reset(); // learned, or screened out: the sums are no longer needed
    }
    if (!reads_film(sample_index))
        return true;
    if (!film)
        throw Error("a verdict pass without its film (a bug)");
    const int64_t verdict_pass = int64_t(sample_index) - verdict_start();
    // The verdict's kept passes, then the fallback's, then the choice.
    if (!verdict_)
        verdict_ = std::make_unique<GuideVerdict>(
            film->width(), film->height(), options_.verdict_passes,
            alternative_kept_ ? options_.alternative_cost
                              : verdict_cost_for(options_, scene_.params.guide_continuation != 0));
    verdict_->add(1, static_cast<int>(verdict_pass), &film->film_sum[0].x);
    if (verdict_pass + 1 < options_.verdict_passes)
        return true;
    const Timer t;
    const bool whole = give_verdict(measure);
    verdict_seconds_ += t.seconds();
    if (!switches_.empty() && cache_) { // no more learning; the last records, counted
        take_records(device);
        cache_.reset();
    }
    return whole;
}

bool VisibilityLearning::give_verdict(const MeasuringPass& measure) {
    for (int k = 0; k < options_.verdict_passes; ++k) {
        etk::EtkParams p = scene_.params;
        p.sample_index = kVerdictFallbackBase + static_cast<uint32_t>(k);
        p.pixel_stride = options_.verdict_stride;
        configure(p, p.sample_index, false);
        const Film* film = measure(p);
        if (!film)
            return false;
        verdict_->add(0, k, &film->film_sum[0].x);
    }
    const int end = verdict_start() + options_.verdict_passes;
    if (!verdict_->kept_wins())
        switch_to(end, options_.fallback);
    else if (alternative_kept_) // (the same technique: the learning's passes end here)
        switch_to(end, options_.alternative);
    if (!alternative_kept_) // (else the screen chose what the verdict weighed)
        verdict_by_ = "measure";
    decided_ = measured_ = true;
    verdict_fallback_error_ = verdict_->fallback_error();
    verdict_kept_error_ = verdict_->kept_error();
    verdict_log_ratio_se_ = verdict_->log_ratio_se();
    verdict_.reset();
    return true;
}

nlohmann::json VisibilityLearning::stats() const {
    nlohmann::json counts = nlohmann::json::object();
    for (const auto& [n, cells] : light_counts_)
        counts[nlohmann::json(n).dump()] = cells; // keys "0.5", "0.25", "0.125"
    // The learning's length: where its plan ends it, or where another technique begins (the
    // passes from there learn nothing). What the verdict weighed: nothing where the screen
    // decided alone.
    const Strategy kept = kept_technique();
    const char* kept_name = decided_ && !measured_         ? "none"
                            : kept == Strategy::visibility ? "tables"
                                                           : name_of(kept);
    return {{"learning_passes", learn_until_},
            {"learned_passes", learned_passes_},
            {"learning_seconds", learning_seconds_},
            {"update_seconds", update_seconds_},
            {"records", records_},
            {"continuation_records", continuation_records_},
            {"host_bytes", host_bytes_},
            {"device_bytes", device_bytes_},
            {"cells_with_fewer_light_samples", counts},
            {"cells_with_portal_share", portal_cells_},
            {"verdict", !decided_           ? "none"
                        : switches_.empty() ? "tables"
                                            : name_of(switches_.back().technique)},
            {"verdict_by", verdict_by_},
            {"verdict_measured", measured_},
            {"verdict_fallback", name_of(options_.fallback)},
            {"verdict_screen_share", screen_share_},
            {"verdict_passes", options_.verdict_passes},
            {"verdict_stride", options_.verdict_stride},
            {"verdict_cost",
             alternative_kept_ ? options_.alternative_cost
                               : verdict_cost_for(options_, scene_.params.guide_continuation != 0)},
            {"verdict_seconds", verdict_seconds_},
            {"verdict_fallback_error", verdict_fallback_error_},
            {"verdict_kept", kept_name},
            {"verdict_kept_error", verdict_kept_error_},
            {"verdict_log_ratio_se", verdict_log_ratio_se_}};
}

} // namespace et
