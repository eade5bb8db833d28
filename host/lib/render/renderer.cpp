#include "render/renderer.h"

#include "render/executor_cl.h"
#include "render/executor_cpu.h"
#include "util/error.h"
#include "util/timer.h"

#include <algorithm>
#include <string>

namespace et {

Renderer::Renderer(const DeviceScene& scene, const DeviceFactory& make_device)
    : scene_(scene), film_(scene.width(), scene.height()), device_(make_device(film_)) {}

void Renderer::render_sample(uint32_t sample_index) {
    Timer timer;
    etk::EtkParams p = scene_.params;
    p.sample_index = sample_index;
    const RayCounts c = run_pass(*device_, p);
    stats_.camera_rays += c.camera;
    stats_.continuation_rays += c.continuation;
    stats_.shadow_rays += c.shadow;
    stats_.nonfinite_samples += c.nonfinite;
    stats_.shaded_hits += c.shaded;
    stats_.samples_per_pixel += 1;
    stats_.seconds += timer.seconds();
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
