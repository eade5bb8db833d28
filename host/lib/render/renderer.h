// The renderer: a prepared scene, a back end (OpenCL or native) and the film. Each pass adds
// one sample to every pixel by running the one bounce schedule (schedule.h) on the back end,
// into a zeroed device film that is then added, exactly, to the film's sums (film_sums.h): the
// image does not depend on which process rendered which sample index, or in which order.
// Path tracing, SIS and directional light sets are all this renderer; the strategy in the
// scene's settings picks the stages.
#pragma once
#include "opencl/opencl_runtime.h"
#include "prepare/device_scene.h"
#include "render/film.h"
#include "render/film_sums.h"
#include "render/guide_verdict.h"
#include "render/light_share.h"
#include "render/schedule.h"
#include "render/visibility_cache.h"

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace et {

struct RenderStats {
    uint64_t camera_rays = 0, continuation_rays = 0, shadow_rays = 0;
    uint64_t nonfinite_samples = 0; // dropped by the film; anything but 0 is a bug
    uint64_t shaded_hits = 0;       // surface hits shaded
    int samples_per_pixel = 0;
    int learning_passes = 0; // adaptive: passes rendered only to learn (resumes, sample ranges)
    double seconds = 0.0;
    // Visibility strategy: learning passes' time (records read and summed included), the
    // tables' rebuilds and uploads, records (shadow rays', continuations'), and the learned
    // structure's memory.
    double guide_learning_seconds = 0.0, guide_update_seconds = 0.0;
    double guide_record_seconds = 0.0; // of the learning passes: records read back and added
    int guide_record_threads = 0;      // the most host threads they were added on at once
    uint64_t guide_records = 0, guide_continuation_records = 0;
    uint64_t guide_host_bytes = 0, guide_device_bytes = 0;
    // The learned tables' cells that take fewer light samples (etk_guide_light_count), per count.
    std::map<float, uint64_t> guide_light_counts;
    // Its verdict (guide_verdict.h): 1 the tables stay, 0 MIS from then on, -1 not (yet) given;
    // the two techniques' measured errors per sample.
    int guide_verdict = -1;
    double guide_verdict_mis_error = 0.0, guide_verdict_tables_error = 0.0;
    double guide_verdict_seconds = 0.0; // its MIS passes (rendered to measure, not kept)
    // Time per stage (seconds): device time from profiling events for OpenCL, thread time natively.
    std::vector<std::pair<std::string, double>> stage_seconds;
    uint64_t rays() const { return camera_rays + continuation_rays + shadow_rays; }
};

// Makes the back end for a film (the native one renders into it in place).
using DeviceFactory = std::function<std::unique_ptr<WavefrontDevice>(Film& film)>;

class Renderer {
  public:
    // `scene` must outlive the renderer.
    Renderer(const DeviceScene& scene, const DeviceFactory& make_device);
    // Adds one sample to every pixel (index `sample_index` of each pixel's sequence). The
    // adaptive strategy learns from samples 0 .. L-1; a render that starts past them (a resume,
    // a sample range, an MPI rank) first renders them to learn, without adding them to its sums.
    // Returns false where the stop request (set_stop) abandoned it: nothing was added, and the
    // renderer renders no more (its learning may be half done); its sums stay whole.
    bool render_sample(uint32_t sample_index);
    // Asked between waves and bounces of every pass from now on (schedule.h).
    void set_stop(StopRequest stop) { stop_ = std::move(stop); }
    // Whether a stop request abandoned a pass (a whole sample may still have been added: the
    // visibility verdict's measuring passes come after it); render_sample may not be called again.
    bool abandoned() const { return abandoned_; }
    // With hold, render_sample keeps its sample aside until keep_held() adds it to the sums or
    // drop_held() discards it (MPI ranks keep a round only if no rank abandoned theirs); the
    // next render_sample needs one of the two first.
    void set_hold(bool hold) { hold_ = hold; }
    void keep_held();
    void drop_held() {
        stats_.samples_per_pixel -= held_ ? 1 : 0;
        held_ = false;
    }
    // Adaptive strategy: light share and ETK_BIN_* flags per material bin for the passes to come,
    // and the learned candidate per bin (-1 before or without learning).
    const std::array<float, ETK_SHARE_BINS>& light_shares() const { return shares_; }
    const std::array<int, ETK_SHARE_BINS>& bin_flags() const { return flags_; }
    const std::array<int, ETK_SHARE_BINS>& choices() const { return choices_; }
    // The sums of every sample rendered (and resumed from) so far.
    const FilmSums& sums() const { return sums_; }
    // Whether the sample_lights stage draws the light samples (RenderSettings::light_batch).
    bool batches_light_samples() const { return light_batch_; }
    // Continues from sums of the same size (an earlier, interrupted render, or another rank's).
    void resume(const FilmSums& sums);
    // Mean radiance per pixel (RGB, row-major, row 0 at the top).
    std::vector<float> image() const { return sums_.mean(); }
    const RenderStats& stats();
    int paths() const { return device_->lanes() * device_->wave_size(); }
    std::string name() const { return device_->name(); }

  private:
    // One pass into the zeroed film; learning pass if `learn`; added to the sums (or held) if
    // `keep`. False where the stop request abandoned it.
    bool run(uint32_t sample_index, bool learn, bool keep);
    const DeviceScene& scene_;
    Film film_; // one pass; declared before device_: the native back end writes into it
    FilmSums sums_;
    std::unique_ptr<WavefrontDevice> device_;
    RenderStats stats_;
    std::array<float, ETK_SHARE_BINS> shares_;
    std::array<int, ETK_SHARE_BINS> flags_, choices_;
    bool light_batch_ = false;
    StopRequest stop_;
    bool hold_ = false, held_ = false; // set_hold; a sample waits in held_film_
    Film held_film_;
    bool abandoned_ = false;     // a stop request ended a pass: no more rendering
    bool learning_ = false;      // adaptive strategy, configuration learned (not fixed)
    int next_learning_pass_ = 0; // the learning pass that comes next (L: learned)
    LightShareOptions options_;
    std::unique_ptr<LightShareLearner> learner_;
    bool guide_ = false;       // visibility strategy
    bool guide_ready_ = false; // its tables hold something to sample: learned (visibility) or
                               // prepared with the map (cosine)
    VisibilityOptions guide_options_;
    std::unique_ptr<VisibilityCache> cache_;
    std::unique_ptr<GuideVerdict> verdict_;
    bool guide_dropped_ = false;   // the verdict chose MIS: the passes after it render MIS
    bool mis_light_batch_ = false; // the sample_lights stage for those passes
    int learning_pass_count() const;
    int verdict_start() const; // the first of the visibility verdict's passes of the tables
    // The parameters of pass `sample_index` of the visibility strategy: its tables', or MIS's
    // for the verdict's measuring passes and after a verdict for MIS.
    void set_guide_pass(etk::EtkParams& p, uint32_t sample_index) const;
    // After the verdict's passes of the tables: its passes of MIS (sample indices
    // kVerdictMisBase + k, never kept: they measure MIS without adding its variance to the
    // image), and the choice.
    void give_verdict();
    void count(const RayCounts& c);
    static constexpr uint32_t kVerdictMisBase = 0x80000000u;
};

// The renderer for scene.settings (back end, device, paths in flight, threads). `build`
// receives the OpenCL program build time (untouched for the native back end).
std::unique_ptr<Renderer> make_renderer(const DeviceScene& scene,
                                        ProgramBuildInfo* build = nullptr);

} // namespace et
