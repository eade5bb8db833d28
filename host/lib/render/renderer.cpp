#include "render/renderer.h"

#include "render/executor_cl.h"
#include "render/executor_cpu.h"
#include "util/error.h"
#include "util/timer.h"

#include <algorithm>
#include <string>

namespace et {

Renderer::Renderer(const DeviceScene& scene, const DeviceFactory& make_device)
    : scene_(scene), film_(scene.width(), scene.height()), sums_(scene.width(), scene.height()),
      device_(make_device(film_)) {}

void Renderer::render_sample(uint32_t sample_index) {
    Timer timer;
    etk::EtkParams p = scene_.params;
    p.sample_index = sample_index;
    // The pass renders into a zeroed film (element-wise: the native back end holds pointers
    // into film_), whose one sample per pixel is then added exactly to the sums.
#define ET_ZERO(type, name) std::fill(film_.name.begin(), film_.name.end(), type{});
    ETK_FILM_FIELDS(ET_ZERO)
#undef ET_ZERO
    device_->upload_film(film_);
    const RayCounts c = run_pass(*device_, p);
    device_->download_film(film_);
    sums_.add_pass(film_);
    stats_.camera_rays += c.camera;
    stats_.continuation_rays += c.continuation;
    stats_.shadow_rays += c.shadow;
    stats_.nonfinite_samples += c.nonfinite;
    stats_.shaded_hits += c.shaded;
    stats_.samples_per_pixel += 1;
    stats_.seconds += timer.seconds();
}

void Renderer::resume(const FilmSums& sums) {
    if (sums.width() != sums_.width() || sums.height() != sums_.height())
        throw Error("cannot resume a " + std::to_string(sums_.width()) + "x" +
                    std::to_string(sums_.height()) + " render from a " +
                    std::to_string(sums.width()) + "x" + std::to_string(sums.height()) + " film");
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
