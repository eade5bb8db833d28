#include "render/schedule.h"

#include "prepare/technique.h"
#include "render/learning_policy.h"
#include "util/error.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace et {

const char* stage_name(int stage) {
#define ET_STAGE_NAME(kernel, fn, pushes) #kernel,
    static const char* const names[] = {ETK_STAGES(ET_STAGE_NAME)};
#undef ET_STAGE_NAME
    return stage >= 0 && stage < etk::ETK_STAGE_COUNT ? names[stage] : "?";
}

size_t path_field_bytes(int field) {
    using etk::EtkGuideVertices;
    using etk::float2;
    using etk::float4;
#define ET_FIELD_BYTES(type, name) sizeof(type),
    static const size_t bytes[] = {ETK_PATH_FIELDS(ET_FIELD_BYTES)};
#undef ET_FIELD_BYTES
    if (field < 0 || field >= etk::ETK_FIELD_COUNT)
        throw Error("no path field " + std::to_string(field) + " (a bug)");
    return bytes[field];
}

void WavefrontDevice::upload_guide(const std::vector<float>&, const std::vector<FloatSpan>&) {
    throw Error("this back end cannot take the visibility strategy's tables");
}

void WavefrontDevice::absorb_guide_sums(const GuideSumsAbsorb&) {
    throw Error("this back end keeps no visibility records");
}

void WavefrontDevice::fold_film() {
    throw Error("this back end keeps no film sums (a bug)");
}

void WavefrontDevice::take_film_sums(FilmSums&) {
    throw Error("this back end keeps no film sums (a bug)");
}

RayCounts& RayCounts::operator+=(const RayCounts& o) {
    camera += o.camera;
    continuation += o.continuation;
    shadow += o.shadow;
    shaded += o.shaded;
    nonfinite += o.nonfinite;
    abandoned = abandoned || o.abandoned;
    return *this;
}

bool run_wave(StageExecutor& ex, etk::EtkParams p, int first, int n, RayCounts& counts,
              const StopRequest& stop) {
    p.first_pixel = first;
    p.pixel_stride = std::max(1, p.pixel_stride);
    // A light set sums all its lights at a hit; every other technique takes one light sample.
    const int shade =
        technique_uses_light_set(p) ? etk::ETK_STAGE_shade_lights : etk::ETK_STAGE_shade_hits;
    uint32_t c[etk::ETK_Q_COUNT];
    ex.bind_queues(true); // generate fills queue A
    ex.launch(etk::ETK_STAGE_generate, n, p);
    counts.camera += n;
    int rays = n;
    bool swapped = false;
    for (int bounce = 0; rays > 0; ++bounce) {
        if (bounce > 0)
            counts.continuation += rays;
        ex.bind_queues(swapped);
        ex.reset_counters();
        ex.launch(etk::ETK_STAGE_intersect, rays, p); // lights the escaped rays itself
        ex.read_counters(c);
        if (p.light_batch) // the shade queue's light samples, ETK_LIGHT_BATCH per work-item
            ex.launch(
                etk::ETK_STAGE_sample_lights,
                static_cast<int>((c[etk::ETK_Q_SHADE] + ETK_LIGHT_BATCH - 1) / ETK_LIGHT_BATCH), p);
        ex.launch(shade, static_cast<int>(c[etk::ETK_Q_SHADE]), p);
        counts.shaded += c[etk::ETK_Q_SHADE];
        ex.read_counters(c);
        ex.launch(etk::ETK_STAGE_trace_shadows, static_cast<int>(c[etk::ETK_Q_SHADOW]), p);
        counts.shadow += c[etk::ETK_Q_SHADOW] + c[etk::ETK_Q_LIGHT_RAYS];
        rays = static_cast<int>(c[etk::ETK_Q_RAY_OUT]);
        swapped = !swapped;
        if (rays > 0 && stop && stop())
            return false; // the path state is left as it is: the next wave starts afresh
    }
    ex.launch(etk::ETK_STAGE_accumulate, n, p);
    ex.read_counters(c); // the last bounce reset them: this is the film's count
    counts.nonfinite += c[etk::ETK_Q_NONFINITE];
    return true;
}

RayCounts run_pass(WavefrontDevice& device, const etk::EtkParams& params, const StopRequest& stop) {
    // Paths for pixels 0, stride, 2 stride ...: path k of the pass is pixel k x stride.
    const int stride = std::max(1, params.pixel_stride);
    // Waves no larger than an even share of the pass, so that a pass of few paths (the verdict's
    // every 8th pixel, a small film) still keeps every lane busy.
    const int paths = (params.width * params.height + stride - 1) / stride,
              wave = std::min(device.wave_size(), std::max(1, (paths + device.lanes() - 1) /
                                                                  std::max(1, device.lanes())));
    std::atomic<int> next{0};
    std::atomic<bool> abandoned{false};
    std::vector<RayCounts> counts(device.lanes());
    device.run_lanes([&](int k) {
        for (;;) {
            const int first = next.fetch_add(wave);
            if (first >= paths)
                break; // (the pass may be whole: no stop asked for once every wave is out)
            if (abandoned.load() || (stop && stop())) {
                abandoned = true;
                break;
            }
            const int n = std::min(wave, paths - first);
            if (!run_wave(device.lane(k), params, first * stride, n, counts[k], stop)) {
                abandoned = true;
                break;
            }
        }
    });
    device.finish();
    RayCounts total;
    for (const RayCounts& c : counts)
        total += c;
    total.abandoned = abandoned.load();
    return total;
}

} // namespace et
