// The renderer: a prepared scene, a back end (OpenCL or native) and the film. Each pass adds
// one sample to every pixel by running the one bounce schedule (schedule.h) on the back end,
// into a zeroed device film that is then added, exactly, to the film's sums (film_sums.h): the
// image does not depend on which process rendered which sample index, or in which order.
// Path tracing, SIS and directional light sets are all this renderer; the technique switches in
// the scene's parameters pick the stages, and a learning technique's policy (learning_policy.h)
// adds its learning.
#pragma once
#include "opencl/opencl_runtime.h"
#include "prepare/device_scene.h"
#include "render/film.h"
#include "render/film_sums.h"
#include "render/learning_policy.h"
#include "render/schedule.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace et {

struct RenderStats {
    uint64_t camera_rays = 0, continuation_rays = 0, shadow_rays = 0;
    uint64_t nonfinite_samples = 0; // dropped by the film; anything but 0 is a bug
    uint64_t shaded_hits = 0;       // surface hits shaded
    int samples_per_pixel = 0;
    int learning_passes = 0; // passes rendered only to learn (resumes, sample ranges)
    double seconds = 0.0;
    // The learning technique's own figures (LearningPolicy::stats); null where none learns.
    nlohmann::json learning;
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
    // Adds one sample to every pixel (index `sample_index` of each pixel's sequence). A
    // learning technique learns from samples 0 .. L-1; a render that starts past them (a resume,
    // a sample range, an MPI rank) first renders them to learn, without adding them to its sums.
    // Returns false where the stop request (set_stop) abandoned it: nothing was added, and the
    // renderer renders no more (its learning may be half done); its sums stay whole.
    bool render_sample(uint32_t sample_index);
    // Asked between waves and bounces of every pass from now on (schedule.h).
    void set_stop(StopRequest stop) { stop_ = std::move(stop); }
    // The render's plan (LearningPolicy::plan), asked after each learning pass.
    void set_plan(std::function<LearningPlan()> plan) { plan_ = std::move(plan); }
    // Whether a stop request abandoned a pass (a whole sample may still have been added: a
    // learning technique's measuring passes come after it); render_sample may not be called
    // again.
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
    // The sums of every sample rendered (and resumed from) so far (read from the device first
    // where it keeps them: WavefrontDevice::folds_film).
    const FilmSums& sums() const;
    // Whether the device adds the passes to the sums itself (RenderSettings::film_sums); held
    // passes (set_hold: MPI ranks) are added on the host.
    bool sums_on_device() const { return device_->folds_film() && !hold_; }
    // Whether its waves keep their queue sizes on the device (RenderSettings::queue_counts).
    bool queue_counts_on_device() const { return device_->lane(0).counts_on_device(); }
    // Whether the sample_lights stage draws the light samples (RenderSettings::light_batch).
    bool batches_light_samples() const { return light_batch_; }
    // Continues from sums of the same size (an earlier, interrupted render, or another rank's).
    void resume(const FilmSums& sums);
    // Mean radiance per pixel (RGB, row-major, row 0 at the top).
    std::vector<float> image() const { return sums().mean(); }
    const RenderStats& stats();
    int paths() const { return device_->lanes() * device_->wave_size(); }
    std::string name() const { return device_->name(); }

  private:
    // One pass into the zeroed film; the next learning pass if `learn`; added to the sums (or
    // held) if `keep`. False where the stop request abandoned it.
    bool run(uint32_t sample_index, bool learn, bool keep);
    // A learning technique's measuring pass (MeasuringPass): into film_, neither kept nor learnt.
    const Film* measure(const etk::EtkParams& p);
    int learning_passes() const { return policy_ ? policy_->learning_passes() : 0; }
    void count(const RayCounts& c);
    const DeviceScene& scene_;
    Film film_; // one pass; declared before device_: the native back end writes into it
    // The sums, but for the passes the device has added to its own since sums() last took them
    // (device_sums_ahead_): sums() is a const view whose reads bring those over.
    mutable FilmSums sums_;
    mutable bool device_sums_ahead_ = false;
    std::unique_ptr<WavefrontDevice> device_;
    RenderStats stats_;
    bool light_batch_ = false;
    StopRequest stop_;
    std::function<LearningPlan()> plan_;
    bool hold_ = false, held_ = false; // set_hold; a sample waits in held_film_
    Film held_film_;
    bool abandoned_ = false;                 // a stop request ended a pass: no more rendering
    int next_learning_pass_ = 0;             // the learning pass that comes next
    std::unique_ptr<LearningPolicy> policy_; // null: the technique learns nothing
};

// The renderer for scene.settings (back end, device, paths in flight, threads). `build`
// receives the OpenCL program build time (untouched for the native back end). The renderer reads
// the scene's arrays where they are (an OpenCL buffer over host memory, the native kernels): the
// scene must outlive it, so a temporary is refused.
std::unique_ptr<Renderer> make_renderer(const DeviceScene& scene,
                                        ProgramBuildInfo* build = nullptr);
std::unique_ptr<Renderer> make_renderer(const DeviceScene&& scene,
                                        ProgramBuildInfo* build = nullptr) = delete;

} // namespace et
