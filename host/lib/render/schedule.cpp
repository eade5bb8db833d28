#include "render/schedule.h"

#include "render/light_share.h"
#include "render/visibility_cache.h"
#include "util/error.h"

#include <algorithm>
#include <atomic>
#include <vector>

namespace et {

const char* stage_name(int stage) {
#define ET_STAGE_NAME(kernel, fn, pushes) #kernel,
    static const char* const names[] = {ETK_STAGES(ET_STAGE_NAME)};
#undef ET_STAGE_NAME
    return stage >= 0 && stage < etk::ETK_STAGE_COUNT ? names[stage] : "?";
}

void StageExecutor::read_guide(int, int*, float*) {
    throw Error("this back end cannot read the visibility strategy's records");
}

void WavefrontDevice::upload_guide(const std::vector<float>&) {
    throw Error("this back end cannot take the visibility strategy's tables");
}

RayCounts& RayCounts::operator+=(const RayCounts& o) {
    camera += o.camera;
    continuation += o.continuation;
    shadow += o.shadow;
    shaded += o.shaded;
    nonfinite += o.nonfinite;
    return *this;
}

void run_wave(StageExecutor& ex, etk::EtkParams p, int first, int n, RayCounts& counts,
              LightShareLearner* learner, VisibilityCache* guide) {
    p.first_pixel = first;
    std::vector<int> keys;
    std::vector<float> values;
    // A light set sums all its lights at a hit; every other strategy takes one light sample.
    const int shade =
        p.strategy == ETK_STRATEGY_LIGHTS ? etk::ETK_STAGE_shade_lights : etk::ETK_STAGE_shade_hits;
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
        ex.launch(shade, static_cast<int>(c[etk::ETK_Q_SHADE]), p);
        counts.shaded += c[etk::ETK_Q_SHADE];
        ex.read_counters(c);
        ex.launch(etk::ETK_STAGE_trace_shadows, static_cast<int>(c[etk::ETK_Q_SHADOW]), p);
        counts.shadow += c[etk::ETK_Q_SHADOW] + c[etk::ETK_Q_LIGHT_RAYS];
        if (guide && p.guide_learn && c[etk::ETK_Q_SHADOW] > 0) {
            const int m = static_cast<int>(c[etk::ETK_Q_SHADOW]);
            keys.resize(m);
            values.resize(m);
            ex.read_guide(m, keys.data(), values.data());
            guide->add(keys.data(), values.data(), m);
        }
        rays = static_cast<int>(c[etk::ETK_Q_RAY_OUT]);
        swapped = !swapped;
    }
    ex.launch(etk::ETK_STAGE_accumulate, n, p);
    ex.read_counters(c); // the last bounce reset them: this is the film's count
    counts.nonfinite += c[etk::ETK_Q_NONFINITE];
    if (learner && p.learn) {
        ex.read_learning(n, learner->bins_of_pass() + first);
    }
}

RayCounts run_pass(WavefrontDevice& device, const etk::EtkParams& params,
                   LightShareLearner* learner, VisibilityCache* guide) {
    const int pixels = params.width * params.height, wave = device.wave_size();
    std::atomic<int> next{0};
    std::vector<RayCounts> counts(device.lanes());
    device.run_lanes([&](int k) {
        for (;;) {
            const int first = next.fetch_add(wave);
            if (first >= pixels)
                break;
            run_wave(device.lane(k), params, first, std::min(wave, pixels - first), counts[k],
                     learner, guide);
        }
    });
    device.finish();
    RayCounts total;
    for (const RayCounts& c : counts)
        total += c;
    return total;
}

} // namespace et
