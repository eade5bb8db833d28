#include "render/renderer.h"

#include "render/executor_cl.h"
#include "render/executor_cpu.h"
#include "render/film_aovs.h"
#include "util/error.h"
#include "util/file_check.h"
#include "util/timer.h"

#include <algorithm>
#include <string>
#include <cstdio>
#include <sys/resource.h>
#include <unistd.h>

namespace et {

namespace {

// A film the machine cannot hold is an error before anything is allocated, naming its size (a
// 16384 x 16384 film grew to 17 GB over 40 s before "out of memory", or met the OOM killer).
// Per pixel, what the host allocates whatever the back end: the exact sums (and their AOVs), the
// film's fields (all four, AOVs or not) and the image written at the end (mean and preview). A
// device's own copy is the device's to check (executor_cl.cpp: its global memory).
// Memory this process may still take: the kernel's MemAvailable (free memory and what it can
// reclaim), below the address-space limit (ulimit -v) less what is mapped already; 0 if unknown.
uint64_t memory_available() {
    uint64_t have = 0;
    if (std::FILE* f = std::fopen("/proc/meminfo", "r")) {
        char line[128];
        unsigned long long kb = 0;
        while (std::fgets(line, sizeof line, f))
            if (std::sscanf(line, "MemAvailable: %llu kB", &kb) == 1) {
                have = uint64_t(kb) * 1024;
                break;
            }
        std::fclose(f);
    }
    if (have == 0) {
        const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
        have = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : 0;
    }
    struct rlimit rl {};
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        uint64_t mapped = 0;
        if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
            unsigned long long vm_pages = 0;
            if (std::fscanf(f, "%llu", &vm_pages) == 1)
                mapped = uint64_t(vm_pages) * uint64_t(sysconf(_SC_PAGE_SIZE));
            std::fclose(f);
        }
        const uint64_t room = rl.rlim_cur > mapped ? uint64_t(rl.rlim_cur) - mapped : 0;
        have = have == 0 ? room : std::min(have, room);
    }
    return have;
}

int checked_film_width(const DeviceScene& scene) {
    const uint64_t pixels = uint64_t(scene.width()) * uint64_t(scene.height());
    // The film's sums and device buffers, and the outputs' copies of the image (the mean, its
    // preview and the encoders' buffers: 111 bytes a pixel of an RGB image measured, peak 319 in
    // all at 8192 x 8192, where 208 were counted and the film passed, to run out of memory
    // after rendering); AOV layers take 13 channels where the image takes 3.
    const uint64_t channels = scene.settings.aovs ? 13 : 3;
    const uint64_t per_pixel = sizeof(FilmSums::Pixel) +
                               (scene.settings.aovs ? sizeof(AovPixel) : 0) +
                               4 * sizeof(etk::float4) + 8 * sizeof(float) + 37 * channels;
    const uint64_t need = pixels * per_pixel;
    const uint64_t have = memory_available();
    if (have > 0 && need > have)
        throw Error("film " + std::to_string(scene.width()) + " x " +
                    std::to_string(scene.height()) + " (film.width, film.height) needs about " +
                    byte_text(need) + " for its sums, buffers and outputs, more than the " +
                    byte_text(have) + " of memory available: render a smaller film");
    return scene.width();
}

} // namespace

Renderer::Renderer(const DeviceScene& scene, const DeviceFactory& make_device)
    : scene_(scene), film_(checked_film_width(scene), scene.height()),
      sums_(scene.width(), scene.height(), scene.settings.aovs), device_(make_device(film_)) {
    std::copy(scene.params.light_share, scene.params.light_share + ETK_SHARE_BINS, shares_.begin());
    std::copy(scene.params.bin_flags, scene.params.bin_flags + ETK_SHARE_BINS, flags_.begin());
    choices_.fill(-1);
    const bool batches_wanted =
        scene.settings.light_batch == LightBatch::on ||
        (scene.settings.light_batch == LightBatch::automatic && device_->prefers_light_batches());
    light_batch_ = scene.params.light_batch != 0 && batches_wanted;
    mis_light_batch_ = etk::etk_batches_light_samples(ETK_STRATEGY_MIS) && batches_wanted;
    learning_ = scene.settings.strategy == Strategy::adaptive && scene.settings.light_share < 0.0f;
    options_.last_bounce = scene.settings.max_depth <= 1;
    guide_ = scene.settings.strategy == Strategy::visibility;
    guide_ready_ = scene.settings.strategy == Strategy::cosine; // its tables are prepared
    if (guide_) {
        guide_options_ = scene.guide_options;
        guide_options_.continuation = scene.params.guide_continuation != 0;
        std::array<float, 6> box;
        const float* table =
            scene.guide_cells.data() +
            etk::etk_portal_offset(guide_options_.slots, guide_options_.continuation ? 1 : 0);
        std::copy(table, table + 6, box.begin());
        cache_ = std::make_unique<VisibilityCache>(guide_options_, scene.guide_regions,
                                                   scene.guide_map_power, box);
        stats_.guide_host_bytes = cache_->bytes();
        stats_.guide_device_bytes =
            (scene.guide_cells.size() + scene.guide_regions.size()) * sizeof(float);
    }
}

int Renderer::verdict_start() const {
    return std::min(guide_options_.learning_passes, guide_options_.verdict_after);
}

int Renderer::learning_pass_count() const {
    if (learning_)
        return options_.learning_passes;
    if (!guide_)
        return 0;
    // The passes the tables learn from and the verdict's; a verdict for MIS ends the learning.
    const int verdict_end =
        guide_options_.verdict_passes > 0 ? verdict_start() + guide_options_.verdict_passes : 0;
    return guide_dropped_ ? verdict_end : std::max(guide_options_.learning_passes, verdict_end);
}

void Renderer::set_guide_pass(etk::EtkParams& p, uint32_t sample_index) const {
    // The verdict's measuring passes (sample indices of their own) and, after a verdict for it,
    // every pass: the paper's estimator, with the strategy's MIS heuristic and GGX sampling.
    const bool mis = sample_index >= kVerdictMisBase || guide_dropped_;
    if (mis) {
        p.strategy = ETK_STRATEGY_MIS;
        p.light_batch = mis_light_batch_ ? 1 : 0;
        p.guide_ready = 0;
    }
    p.guide_learn =
        !mis && p.guide_learn && sample_index < uint32_t(guide_options_.learning_passes) ? 1 : 0;
}

void Renderer::give_verdict() {
    const int v = guide_options_.verdict_passes;
    for (int k = 0; k < v; ++k) {
        etk::EtkParams p = scene_.params;
        p.sample_index = kVerdictMisBase + static_cast<uint32_t>(k);
        set_guide_pass(p, p.sample_index);
        device_->clear_film(sums_.has_aovs());
        const RayCounts c = run_pass(*device_, p, nullptr, nullptr, stop_);
        count(c);
        if (c.abandoned) {
            abandoned_ = true;
            return;
        }
        device_->download_film(film_, sums_.has_aovs());
        verdict_->add(0, k, &film_.film_sum[0].x);
    }
    guide_dropped_ = !verdict_->tables_win();
    stats_.guide_verdict = guide_dropped_ ? 0 : 1;
    stats_.guide_verdict_mis_error = verdict_->mis_error();
    stats_.guide_verdict_tables_error = verdict_->tables_error();
    verdict_.reset();
}

void Renderer::count(const RayCounts& c) {
    stats_.camera_rays += c.camera;
    stats_.continuation_rays += c.continuation;
    stats_.shadow_rays += c.shadow;
    stats_.nonfinite_samples += c.nonfinite;
    stats_.shaded_hits += c.shaded;
}

bool Renderer::render_sample(uint32_t sample_index) {
    if (abandoned_)
        throw Error("render_sample after an abandoned pass (a bug)");
    if (held_)
        throw Error("render_sample with a held sample neither kept nor dropped (a bug)");
    Timer timer;
    // Learning needs samples 0 .. L-1 in order; rendered first, and kept only by the process
    // whose first sample is 0.
    // (learning_pass_count() shrinks when the visibility strategy's verdict ends its learning.)
    while (next_learning_pass_ < learning_pass_count() &&
           sample_index != static_cast<uint32_t>(next_learning_pass_)) {
        if (!run(static_cast<uint32_t>(next_learning_pass_), true, false)) {
            stats_.seconds += timer.seconds();
            return false;
        }
        ++stats_.learning_passes;
    }
    // (A stop during the visibility verdict's passes after it leaves this sample whole.)
    const bool whole = run(sample_index, next_learning_pass_ < learning_pass_count(), true);
    if (whole)
        stats_.samples_per_pixel += 1;
    stats_.seconds += timer.seconds();
    return whole;
}

void Renderer::keep_held() {
    if (held_)
        sums_.add_pass(held_film_, scene_.settings.threads);
    held_ = false;
}

bool Renderer::run(uint32_t sample_index, bool learn, bool keep) {
    etk::EtkParams p = scene_.params;
    p.sample_index = sample_index;
    p.light_batch = light_batch_ ? 1 : 0;
    std::copy(shares_.begin(), shares_.end(), p.light_share);
    std::copy(flags_.begin(), flags_.end(), p.bin_flags);
    // Samples 0 .. L-1 are learning samples whether or not they are learnt from: the image
    // depends on the sample index alone.
    p.learn = learning_ && sample_index < static_cast<uint32_t>(options_.learning_passes);
    p.guide_ready = guide_ready_ ? 1 : 0;
    p.guide_learn = guide_ && learn ? 1 : 0;
    if (guide_)
        set_guide_pass(p, sample_index);
    Timer pass_timer;
    LightShareLearner* learner = nullptr;
    if (learn && learning_) {
        if (!learner_)
            learner_ = std::make_unique<LightShareLearner>(options_, film_.width(), film_.height(),
                                                           scene_.params.seed);
        learner_->begin_pass();
        learner = learner_.get();
    }
    // The pass renders into a zeroed film, whose one sample per pixel is then added exactly to
    // the sums.
    device_->clear_film(sums_.has_aovs());
    const RayCounts c =
        run_pass(*device_, p, learner, p.guide_learn ? cache_.get() : nullptr, stop_);
    stats_.guide_record_seconds += c.guide_record_seconds;
    stats_.guide_record_threads = std::max(stats_.guide_record_threads, c.guide_record_threads);
    if (c.abandoned) { // an incomplete film: neither kept nor learnt from
        abandoned_ = true;
        count(c);
        return false;
    }
    device_->download_film(film_, sums_.has_aovs());
    if (keep && hold_) { // a copy: the verdict's passes below render into film_
        held_film_ = film_;
        held_ = true;
    } else if (keep)
        sums_.add_pass(film_, scene_.settings.threads); // the render's cores, idle now
    if (learn && guide_ && p.guide_learn) {
        // The tables for the passes that follow: rebuilt after passes 1, 2, 4, ... L.
        if (VisibilityCache::update_after(next_learning_pass_, guide_options_.learning_passes)) {
            Timer t;
            device_->upload_guide(cache_->tables());
            guide_ready_ = true;
            stats_.guide_light_counts = cache_->fewer_light_samples();
            stats_.guide_update_seconds += t.seconds();
        }
        stats_.guide_records = cache_->records();
        stats_.guide_continuation_records = cache_->continuation_records();
        stats_.guide_learning_seconds += pass_timer.seconds();
        if (next_learning_pass_ + 1 == guide_options_.learning_passes)
            cache_.reset(); // learned: the sums are no longer needed
    }
    const int64_t verdict_pass = int64_t(sample_index) - verdict_start();
    if (learn && guide_ && verdict_pass >= 0 && verdict_pass < guide_options_.verdict_passes) {
        // The verdict's passes of the tables (guide_verdict.h), then MIS's, then the choice.
        if (!verdict_)
            verdict_ = std::make_unique<GuideVerdict>(
                film_.width(), film_.height(), guide_options_.verdict_passes,
                verdict_cost_for(guide_options_, scene_.params.guide_continuation != 0));
        verdict_->add(1, static_cast<int>(verdict_pass), &film_.film_sum[0].x);
        if (verdict_pass + 1 == guide_options_.verdict_passes) {
            Timer t;
            give_verdict();
            stats_.guide_verdict_seconds += t.seconds();
            if (guide_dropped_)
                cache_.reset(); // no more learning
        }
    }
    if (learn && learning_) {
        learner->end_pass(film_.film_sum);
        if (next_learning_pass_ + 1 == options_.learning_passes) {
            choices_ = learner_->choices();
            for (int b = 0; b < ETK_SHARE_BINS; ++b) {
                shares_[b] = etk::etk_learning_share(choices_[b], options_.last_bounce);
                flags_[b] = etk::etk_learning_flags(choices_[b]);
            }
            learner_.reset();
        }
    }
    if (learn)
        ++next_learning_pass_;
    count(c);
    return true;
}

void Renderer::resume(const FilmSums& sums) {
    if (sums.width() != sums_.width() || sums.height() != sums_.height())
        throw Error("cannot resume a " + std::to_string(sums_.width()) + "x" +
                    std::to_string(sums_.height()) + " render from a " +
                    std::to_string(sums.width()) + "x" + std::to_string(sums.height()) + " film");
    if (sums.has_aovs() != sums_.has_aovs())
        throw Error(std::string("cannot resume a render ") +
                    (sums_.has_aovs() ? "with" : "without") + " AOVs from a film " +
                    (sums.has_aovs() ? "with" : "without") + " them");
    sums_ = sums;
}

const RenderStats& Renderer::stats() {
    stats_.stage_seconds = device_->stage_seconds();
    return stats_;
}

std::unique_ptr<Renderer> make_renderer(const DeviceScene& scene, ProgramBuildInfo* build) {
    const RenderSettings& st = scene.settings;
    DeviceFactory factory;
    switch (st.backend) {
    case Backend::opencl:
        factory = [&](Film&) -> std::unique_ptr<WavefrontDevice> {
            return std::make_unique<ClDevice>(std::make_unique<ClRuntime>(st.device), scene,
                                              st.paths, build);
        };
        break;
    case Backend::cpu:
        factory = [&](Film& film) -> std::unique_ptr<WavefrontDevice> {
            return std::make_unique<CpuDevice>(scene, film, st.threads);
        };
        break;
    }
    return std::make_unique<Renderer>(scene, factory);
}

} // namespace et
