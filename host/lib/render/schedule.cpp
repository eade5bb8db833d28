#include "render/schedule.h"

#include "kernels/integrator.h"

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

void StageExecutor::next_bounce(int) {
    throw Error("this executor keeps its queue sizes on the host (a bug)");
}

void StageExecutor::launch_counted(int, int, const etk::EtkParams&) {
    throw Error("this executor keeps its queue sizes on the host (a bug)");
}

namespace {

// Where a wave stands between two bounces: the next bounce, which queue buffer holds its rays,
// and how many there are.
struct WaveAt {
    int bounce = 0;
    bool swapped = false;
    int rays = 0;
};

// The shade stage of the pass's technique: a light set sums all its lights at a hit; every other
// technique takes one light sample.
int shade_stage(const etk::EtkParams& p) {
    return technique_uses_light_set(p) ? etk::ETK_STAGE_shade_lights : etk::ETK_STAGE_shade_hits;
}

// The most bounces a wave counted on the device enqueues before the host reads the counters: a
// path of max_depth surfaces takes max_depth + 1 (its last ray only intersects), so at the usual
// depths the wave's first read is its last; past this many, the host counts the rest.
constexpr int kDeviceBounces = 16;

// Bounces of a wave of n paths with the queue sizes on the device (StageExecutor::
// counts_on_device): each bounce's stages enqueued without waiting, launched for the most entries
// their queue could hold (n; the light batches of n), then one read of the counters. Leaves the
// wave where the host's bounces take it on, if any ray is left.
void device_bounces(StageExecutor& ex, const etk::EtkParams& p, int n, RayCounts& counts,
                    WaveAt& at) {
    const int bounces = std::min(kDeviceBounces, std::max(1, p.max_depth + 1));
    ex.reset_counters();
    for (; at.bounce < bounces; ++at.bounce) {
        ex.bind_queues(at.swapped);
        ex.next_bounce(at.bounce == 0 ? n : -1);
        ex.launch_counted(etk::ETK_STAGE_intersect, n, p);
        if (p.light_batch)
            ex.launch_counted(etk::ETK_STAGE_sample_lights,
                              etk::etk_light_batch_items(static_cast<uint32_t>(n)), p);
        ex.launch_counted(shade_stage(p), n, p);
        ex.launch_counted(etk::ETK_STAGE_trace_shadows, n, p);
        at.swapped = !at.swapped;
    }
    uint32_t c[etk::ETK_Q_COUNT];
    ex.read_counters(c); // the last bounce's counts are not in the sums yet
    counts.continuation += c[etk::ETK_Q_SUM_RAYS_IN];
    counts.shaded += uint64_t(c[etk::ETK_Q_SUM_SHADE]) + c[etk::ETK_Q_SHADE];
    counts.shadow +=
        uint64_t(c[etk::ETK_Q_SUM_SHADOW]) + c[etk::ETK_Q_SHADOW] + c[etk::ETK_Q_LIGHT_RAYS];
    at.rays = static_cast<int>(c[etk::ETK_Q_RAY_OUT]);
}

// Bounces with the queue sizes read by the host, from `at` until no ray is left: false where a
// stop request ended the wave.
bool host_bounces(StageExecutor& ex, const etk::EtkParams& p, RayCounts& counts, WaveAt& at,
                  const StopRequest& stop) {
    uint32_t c[etk::ETK_Q_COUNT];
    for (; at.rays > 0; ++at.bounce) {
        if (at.bounce > 0)
            counts.continuation += at.rays;
        ex.bind_queues(at.swapped);
        ex.reset_counters();
        ex.launch(etk::ETK_STAGE_intersect, at.rays, p); // lights the escaped rays itself
        ex.read_counters(c);
        if (p.light_batch) // the shade queue's light samples, ETK_LIGHT_BATCH per work-item
            ex.launch(etk::ETK_STAGE_sample_lights, etk::etk_light_batch_items(c[etk::ETK_Q_SHADE]),
                      p);
        ex.launch(shade_stage(p), static_cast<int>(c[etk::ETK_Q_SHADE]), p);
        counts.shaded += c[etk::ETK_Q_SHADE];
        ex.read_counters(c);
        ex.launch(etk::ETK_STAGE_trace_shadows, static_cast<int>(c[etk::ETK_Q_SHADOW]), p);
        counts.shadow += c[etk::ETK_Q_SHADOW] + c[etk::ETK_Q_LIGHT_RAYS];
        at.rays = static_cast<int>(c[etk::ETK_Q_RAY_OUT]);
        at.swapped = !at.swapped;
        if (at.rays > 0 && stop && stop())
            return false; // the path state is left as it is: the next wave starts afresh
    }
    return true;
}

} // namespace

bool run_wave(StageExecutor& ex, etk::EtkParams p, int first, int n, RayCounts& counts,
              const StopRequest& stop) {
    p.first_pixel = first;
    p.pixel_stride = std::max(1, p.pixel_stride);
    ex.bind_queues(true); // generate fills queue A
    ex.launch(etk::ETK_STAGE_generate, n, p);
    counts.camera += n;
    WaveAt at;
    at.rays = n;
    if (ex.counts_on_device())
        device_bounces(ex, p, n, counts, at);
    if (!host_bounces(ex, p, counts, at, stop))
        return false;
    ex.launch(etk::ETK_STAGE_accumulate, n, p);
    uint32_t c[etk::ETK_Q_COUNT];
    ex.read_counters(c); // the last bounce reset them: this is the film's count
    counts.nonfinite += c[etk::ETK_Q_NONFINITE];
    return true;
}

WaveDealer::WaveDealer(int paths, int stride, int wave, int lanes)
    : paths_(std::max(0, paths)), stride_(std::max(1, stride)), wave_(std::max(1, wave)),
      lanes_(std::max(1, lanes)), interleaved_(lanes_ > 1 && lanes_ <= kMostInterleaved &&
                                               int64_t(paths_) <= int64_t(lanes_) * wave_) {}

bool WaveDealer::next(Wave* w) {
    if (interleaved_) {
        const int k = next_.fetch_add(1);
        if (k >= std::min(lanes_, paths_))
            return false;
        *w = {k * stride_, stride_ * lanes_, (paths_ - k + lanes_ - 1) / lanes_};
        return true;
    }
    int first = next_.load(), n = 0;
    do {
        if (first >= paths_)
            return false;
        n = wave_size_for(paths_ - first);
    } while (!next_.compare_exchange_weak(first, first + n));
    *w = {first * stride_, stride_, n};
    return true;
}

int WaveDealer::wave_size_for(int left) const {
    int n = wave_;
    // A 1 / (2 lanes) share of what is left: the lanes' last waves shrink together.
    if (lanes_ > 1) {
        const int64_t share = (int64_t(left) + 2 * lanes_ - 1) / (2 * lanes_);
        n = static_cast<int>(std::min<int64_t>(n, std::max<int64_t>(kTailWave, share)));
    }
    return std::min(n, left);
}

RayCounts run_pass(WavefrontDevice& device, const etk::EtkParams& params, const StopRequest& stop) {
    const int stride = std::max(1, params.pixel_stride);
    // Waves no larger than an even share of the pass, so that a pass of few paths (the verdict's
    // every 8th pixel, a small film) still keeps every lane busy.
    const int paths = (params.width * params.height + stride - 1) / stride,
              lanes = std::max(1, device.lanes()),
              wave = std::min(device.wave_size(), std::max(1, (paths + lanes - 1) / lanes));
    WaveDealer dealer(paths, stride, wave, lanes);
    std::atomic<bool> abandoned{false};
    std::vector<RayCounts> counts(lanes);
    device.run_lanes([&](int k) {
        WaveDealer::Wave w;
        while (dealer.next(&w)) { // (the pass may be whole: no stop asked for once all are out)
            if (abandoned.load() || (stop && stop())) {
                abandoned = true;
                break;
            }
            etk::EtkParams p = params;
            p.pixel_stride = w.pixel_stride;
            if (!run_wave(device.lane(k), p, w.first_pixel, w.n, counts[k], stop)) {
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
