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
    const bool batches_wanted =
        scene.settings.light_batch == LightBatch::on ||
        (scene.settings.light_batch == LightBatch::automatic && device_->prefers_light_batches());
    light_batch_ = scene.params.light_batch != 0 && batches_wanted;
    policy_ = make_learning_policy(scene, batches_wanted);
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
    // whose first sample is 0. (L may shrink as a pass ends the learning early.)
    while (next_learning_pass_ < learning_passes() &&
           sample_index != static_cast<uint32_t>(next_learning_pass_)) {
        if (!run(static_cast<uint32_t>(next_learning_pass_), true, false)) {
            stats_.seconds += timer.seconds();
            return false;
        }
        ++stats_.learning_passes;
    }
    // (A stop during a learning technique's measuring passes after it leaves this sample whole.)
    const bool whole = run(sample_index, next_learning_pass_ < learning_passes(), true);
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

const Film* Renderer::measure(const etk::EtkParams& p) {
    device_->clear_film(sums_.has_aovs());
    const RayCounts c = run_pass(*device_, p, stop_);
    count(c);
    if (c.abandoned) {
        abandoned_ = true;
        return nullptr;
    }
    device_->download_film(film_, sums_.has_aovs());
    return &film_;
}

bool Renderer::run(uint32_t sample_index, bool learn, bool keep) {
    etk::EtkParams p = scene_.params;
    p.sample_index = sample_index;
    p.light_batch = light_batch_ ? 1 : 0;
    if (policy_)
        policy_->configure(p, sample_index, learn);
    Timer pass_timer;
    // The pass renders into a zeroed film, whose one sample per pixel is then added exactly to
    // the sums.
    device_->clear_film(sums_.has_aovs());
    const RayCounts c = run_pass(*device_, p, stop_);
    if (c.abandoned) { // an incomplete film: neither kept nor learnt from
        abandoned_ = true;
        count(c);
        return false;
    }
    // A kept pass is added where the device keeps the sums (not when held: MPI), else on the
    // host; the film comes back only for the host or for a policy that reads it.
    const bool fold = keep && !hold_ && device_->folds_film();
    const bool read = (keep && !fold) || (learn && policy_->reads_film(sample_index));
    if (fold) {
        device_->fold_film();
        device_sums_ahead_ = true;
    }
    if (read)
        device_->download_film(film_, sums_.has_aovs());
    if (keep && hold_) { // a copy: a learning technique's measuring passes render into film_
        held_film_ = film_;
        held_ = true;
    } else if (keep && !fold)
        sums_.add_pass(film_, scene_.settings.threads); // the render's cores, idle now
    if (learn) {
        // (An abandoned measuring pass leaves this pass whole; abandoned_ stops what follows.)
        policy_->plan(plan_ ? plan_() : LearningPlan{});
        policy_->after_pass(next_learning_pass_, sample_index, read ? &film_ : nullptr,
                            pass_timer.seconds(), *device_,
                            [this](const etk::EtkParams& q) { return measure(q); });
        ++next_learning_pass_;
    }
    count(c);
    return true;
}

const FilmSums& Renderer::sums() const {
    if (device_sums_ahead_) {
        device_sums_ahead_ = false; // (a failed read ends the render: never added twice)
        device_->take_film_sums(sums_);
    }
    return sums_;
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
    this->sums(); // (the device's own sums, if any, start again from zero)
    sums_ = sums;
}

const RenderStats& Renderer::stats() {
    stats_.stage_seconds = device_->stage_seconds();
    if (policy_)
        stats_.learning = policy_->stats();
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
