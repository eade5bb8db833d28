#include "render/renderer.h"

#include "render/executor_cl.h"
#include "render/executor_cpu.h"
#include "util/error.h"
#include "util/timer.h"

#include <algorithm>
#include <string>

namespace et {

Renderer::Renderer(const DeviceScene& scene, const DeviceFactory& make_device)
    : scene_(scene), film_(scene.width(), scene.height()), device_(make_device(film_)) {
    std::copy(scene.params.light_share, scene.params.light_share + ETK_SHARE_BINS, shares_.begin());
    std::copy(scene.params.bin_flags, scene.params.bin_flags + ETK_SHARE_BINS, flags_.begin());
    choices_.fill(-1);
    learning_ = scene.settings.strategy == Strategy::adaptive && scene.settings.light_share < 0.0f;
    options_.last_bounce = scene.settings.max_depth <= 1;
}

void Renderer::render_sample(uint32_t sample_index) {
    Timer timer;
    if (learning_ && next_learning_pass_ < options_.learning_passes &&
        sample_index != static_cast<uint32_t>(next_learning_pass_))
        learn_on_scratch_film();
    const bool learn = learning_ && next_learning_pass_ < options_.learning_passes;
    run(sample_index, learn);
    stats_.samples_per_pixel += 1;
    stats_.seconds += timer.seconds();
}

// Samples 0 .. L-1 rendered to learn, on a zeroed film; the film so far is put back afterwards.
void Renderer::learn_on_scratch_film() {
    const Film kept = film();
    Film scratch(film_.width(), film_.height());
    resume(scratch);
    while (next_learning_pass_ < options_.learning_passes) {
        run(static_cast<uint32_t>(next_learning_pass_), true);
        ++stats_.learning_passes;
    }
    resume(kept);
}

// One pass of sample `sample_index`; with `learn`, it is learning pass next_learning_pass_.
void Renderer::run(uint32_t sample_index, bool learn) {
    etk::EtkParams p = scene_.params;
    p.sample_index = sample_index;
    std::copy(shares_.begin(), shares_.end(), p.light_share);
    std::copy(flags_.begin(), flags_.end(), p.bin_flags);
    // Samples 0 .. L-1 are learning samples whether or not they are learnt from (a resume
    // renders them again on a scratch film to learn): the image depends on the sample index
    // alone.
    p.learn = learning_ && sample_index < static_cast<uint32_t>(options_.learning_passes);
    LightShareLearner* learner = nullptr;
    if (learn) {
        if (!learner_)
            learner_ = std::make_unique<LightShareLearner>(options_, film_.width(), film_.height(),
                                                           scene_.params.seed);
        learner_->begin_pass(film().film_sum);
        learner = learner_.get();
    }
    const RayCounts c = run_pass(*device_, p, learner);
    if (learn) {
        learner->end_pass(film().film_sum);
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

const Film& Renderer::film() {
    device_->download_film(film_);
    return film_;
}

void Renderer::resume(const Film& film) {
    if (film.width() != film_.width() || film.height() != film_.height())
        throw Error("cannot resume a " + std::to_string(film_.width()) + "x" +
                    std::to_string(film_.height()) + " render from a " +
                    std::to_string(film.width()) + "x" + std::to_string(film.height()) + " film");
        // Element-wise: the native back end holds pointers into film_.
#define ET_COPY(type, name) std::copy(film.name.begin(), film.name.end(), film_.name.begin());
    ETK_FILM_FIELDS(ET_COPY)
#undef ET_COPY
    device_->upload_film(film_);
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
