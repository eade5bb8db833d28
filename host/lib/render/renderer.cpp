#include "render/renderer.h"

#include "render/executor_cl.h"
#include "render/executor_cpu.h"
#include "util/error.h"
#include "util/timer.h"

#include <algorithm>
#include <string>

namespace et {

Renderer::Renderer(const DeviceScene& scene, const DeviceFactory& make_device)
    : scene_(scene), film_(scene.width(), scene.height()), sums_(scene.width(), scene.height(), scene.settings.aovs),
      device_(make_device(film_)) {
    std::copy(scene.params.light_share, scene.params.light_share + ETK_SHARE_BINS, shares_.begin());
    std::copy(scene.params.bin_flags, scene.params.bin_flags + ETK_SHARE_BINS, flags_.begin());
    choices_.fill(-1);
    learning_ = scene.settings.strategy == Strategy::adaptive && scene.settings.light_share < 0.0f;
    options_.last_bounce = scene.settings.max_depth <= 1;
}

void Renderer::render_sample(uint32_t sample_index) {
    Timer timer;
    // Learning needs samples 0 .. L-1 in order; rendered first, and kept only by the process
    // whose first sample is 0.
    while (learning_ && next_learning_pass_ < options_.learning_passes &&
           sample_index != static_cast<uint32_t>(next_learning_pass_)) {
        run(static_cast<uint32_t>(next_learning_pass_), true, false);
        ++stats_.learning_passes;
    }
    run(sample_index, learning_ && next_learning_pass_ < options_.learning_passes, true);
    stats_.samples_per_pixel += 1;
    stats_.seconds += timer.seconds();
}

void Renderer::run(uint32_t sample_index, bool learn, bool keep) {
    etk::EtkParams p = scene_.params;
    p.sample_index = sample_index;
    std::copy(shares_.begin(), shares_.end(), p.light_share);
    std::copy(flags_.begin(), flags_.end(), p.bin_flags);
    // Samples 0 .. L-1 are learning samples whether or not they are learnt from: the image
    // depends on the sample index alone.
    p.learn = learning_ && sample_index < static_cast<uint32_t>(options_.learning_passes);
    LightShareLearner* learner = nullptr;
    if (learn) {
        if (!learner_)
            learner_ = std::make_unique<LightShareLearner>(options_, film_.width(), film_.height(),
                                                           scene_.params.seed);
        learner_->begin_pass();
        learner = learner_.get();
    }
    // The pass renders into a zeroed film (element-wise: the native back end holds pointers
    // into film_), whose one sample per pixel is then added exactly to the sums.
#define ET_ZERO(type, name) std::fill(film_.name.begin(), film_.name.end(), type{});
    ETK_FILM_FIELDS(ET_ZERO)
#undef ET_ZERO
    device_->upload_film(film_);
    const RayCounts c = run_pass(*device_, p, learner);
    device_->download_film(film_);
    if (keep)
        sums_.add_pass(film_);
    if (learn) {
        learner->end_pass(film_.film_sum);
        if (++next_learning_pass_ == options_.learning_passes) {
            choices_ = learner_->choices();
            for (int b = 0; b < ETK_SHARE_BINS; ++b) {
                shares_[b] = etk::etk_learning_share(choices_[b], options_.last_bounce);
                flags_[b] = etk::etk_learning_flags(choices_[b]);
            }
            learner_.reset();
        }
    }
    stats_.camera_rays += c.camera;
    stats_.continuation_rays += c.continuation;
    stats_.shadow_rays += c.shadow;
    stats_.nonfinite_samples += c.nonfinite;
    stats_.shaded_hits += c.shaded;
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
