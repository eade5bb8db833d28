// The renderer: a prepared scene, a back end (OpenCL or native) and the film. Each pass adds
// one sample to every pixel by running the one bounce schedule (schedule.h) on the back end.
// Path tracing, SIS and directional light sets are all this renderer; the strategy in the
// scene's settings picks the stages.
#pragma once
#include "opencl/opencl_runtime.h"
#include "prepare/device_scene.h"
#include "render/film.h"
#include "render/light_share.h"
#include "render/schedule.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace et {

struct RenderStats {
    uint64_t camera_rays = 0, continuation_rays = 0, shadow_rays = 0;
    uint64_t nonfinite_samples = 0; // dropped by the film; anything but 0 is a bug
    uint64_t shaded_hits = 0;       // surface hits shaded
    int samples_per_pixel = 0;
    int learning_passes = 0; // adaptive: passes rendered only to learn the shares (resumes)
    double seconds = 0.0;
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
    // adaptive strategy learns its light shares from samples 0 .. L-1; a render that starts past
    // them (a resume, a sample range) first renders them on a scratch film to learn the same.
    void render_sample(uint32_t sample_index);
    // Adaptive strategy: light share per material bin (kernels/params.h) for the passes to come.
    const std::array<float, ETK_SHARE_BINS>& light_shares() const { return shares_; }
    const std::array<int, ETK_SHARE_BINS>& bin_flags() const { return flags_; }
    // The learned candidate per bin (etk_learning_share / _flags), -1 before or without learning.
    const std::array<int, ETK_SHARE_BINS>& choices() const { return choices_; }
    bool shares_learned() const {
        return learning_ && next_learning_pass_ >= options_.learning_passes;
    }
    // The film so far (read back from the device).
    const Film& film();
    // Continues from a film of the same size (sums of an earlier, interrupted render).
    void resume(const Film& film);
    // Mean radiance per pixel (RGB, row-major, row 0 at the top).
    std::vector<float> image() { return film().mean(); }
    const RenderStats& stats();
    int paths() const { return device_->lanes() * device_->wave_size(); }
    std::string name() const { return device_->name(); }

  private:
    void run(uint32_t sample_index, bool learn);
    void learn_on_scratch_film();

    const DeviceScene& scene_;
    Film film_; // declared before device_: the native back end writes into it
    std::unique_ptr<WavefrontDevice> device_;
    RenderStats stats_;
    std::array<float, ETK_SHARE_BINS> shares_;
    std::array<int, ETK_SHARE_BINS> flags_, choices_;
    bool learning_ = false;      // adaptive strategy with shares learned (not fixed)
    int next_learning_pass_ = 0; // the learning pass that comes next (L: learned)
    LightShareOptions options_;
    std::unique_ptr<LightShareLearner> learner_;
};

// The renderer for scene.settings (back end, device, paths in flight, threads). `build`
// receives the OpenCL program build time (untouched for the native back end).
std::unique_ptr<Renderer> make_renderer(const DeviceScene& scene,
                                        ProgramBuildInfo* build = nullptr);

} // namespace et
