#include "render/wavefront_cpu.h"
#include "util/parallel.h"

#include "util/timer.h"

#include <algorithm>
#include <atomic>
#include <thread>

namespace et {
namespace {

enum { GENERATE, INTERSECT, ESCAPED, SHADE, SHADOW, ACCUMULATE, STAGES };
const char* kStageNames[] = {"generate",   "intersect",     "escaped_rays",
                             "shade_hits", "trace_shadows", "accumulate"};

// One thread's wavefront: path state and queues for `tile` paths.
struct Lane {
    std::vector<etk::float4> ray_o, ray_d, beta, radiance, hit, shadow_o, shadow_d, shadow_L;
    std::vector<int> pixel, queue_a, queue_b, escaped, shade, shadow;
    uint32_t counters[ETK_Q_COUNT];
    double stage_seconds[STAGES] = {};
    uint64_t camera = 0, continuation = 0, shadow_rays = 0, nonfinite = 0;

    explicit Lane(int n)
        : ray_o(n), ray_d(n), beta(n), radiance(n), hit(n), shadow_o(n), shadow_d(n), shadow_L(n),
          pixel(n), queue_a(n), queue_b(n), escaped(n), shade(n), shadow(n) {}

    etk::EtkPaths paths() {
        return {ray_o.data(),    ray_d.data(),    beta.data(),     radiance.data(), hit.data(),
                shadow_o.data(), shadow_d.data(), shadow_L.data(), pixel.data()};
    }
};

template <typename F> void run_stage(Lane& lane, int stage, int n, F&& f) {
    Timer t;
    for (int i = 0; i < n; ++i)
        f(i);
    lane.stage_seconds[stage] += t.seconds();
}

void render_tile(Lane& lane, const etk::EtkScene& S, etk::EtkParams p, int first, int n,
                 etk::float4* film) {
    p.first_pixel = first;
    etk::EtkPaths P = lane.paths();
    etk::EtkQueues Q{lane.queue_b.data(), lane.queue_a.data(), lane.escaped.data(),
                     lane.shade.data(),   lane.shadow.data(),  lane.counters};
    run_stage(lane, GENERATE, n, [&](int i) { etk::etk_generate(P, Q, p, i); });
    lane.camera += n;
    int rays = n;
    bool swap = false;
    for (int bounce = 0; rays > 0; ++bounce) {
        if (bounce > 0)
            lane.continuation += rays;
        Q.ray_in = swap ? lane.queue_b.data() : lane.queue_a.data();
        Q.ray_out = swap ? lane.queue_a.data() : lane.queue_b.data();
        std::fill(lane.counters, lane.counters + ETK_Q_COUNT, 0u);
        run_stage(lane, INTERSECT, rays, [&](int q) { etk::etk_intersect(P, Q, S, p, q); });
        run_stage(lane, ESCAPED, static_cast<int>(lane.counters[ETK_Q_ESCAPED]),
                  [&](int q) { etk::etk_escaped(P, Q, S, p, q); });
        run_stage(lane, SHADE, static_cast<int>(lane.counters[ETK_Q_SHADE]),
                  [&](int q) { etk::etk_shade(P, Q, S, p, q); });
        run_stage(lane, SHADOW, static_cast<int>(lane.counters[ETK_Q_SHADOW]),
                  [&](int q) { etk::etk_shadow(P, Q, S, q); });
        lane.shadow_rays += lane.counters[ETK_Q_SHADOW];
        rays = static_cast<int>(lane.counters[ETK_Q_RAY_OUT]);
        swap = !swap;
    }
    run_stage(lane, ACCUMULATE, n, [&](int i) { etk::etk_accumulate(P, Q, film, i); });
    lane.nonfinite += lane.counters[ETK_Q_NONFINITE];
}

} // namespace

WavefrontCPU::WavefrontCPU(const SceneArrays& arrays, const etk::EtkParams& params, int threads,
                           int tile)
    : arrays_(arrays), params_(params), pixels_(params.width * params.height) {
    threads_ = thread_count(threads);
    tile_ = tile > 0 ? tile : 1024;
    film_.assign(pixels_, etk::make_float4(0, 0, 0, 0));
}

void WavefrontCPU::render_sample(uint32_t sample_index) {
    Timer timer;
    etk::EtkParams p = params_;
    p.sample_index = sample_index;
    const SceneArrays& a = arrays_;
    const etk::EtkScene S = scene_view(a);
    std::atomic<int> next{0};
    std::vector<Lane> lanes;
    lanes.reserve(threads_);
    for (int t = 0; t < threads_; ++t)
        lanes.emplace_back(tile_);
    auto work = [&](int t) {
        for (;;) {
            const int first = next.fetch_add(tile_);
            if (first >= pixels_)
                break;
            render_tile(lanes[t], S, p, first, std::min(tile_, pixels_ - first), film_.data());
        }
    };
    run_on_threads(threads_, work);
    if (stats_.stage_seconds.empty())
        for (const char* n : kStageNames)
            stats_.stage_seconds.emplace_back(n, 0.0);
    for (const Lane& l : lanes) {
        stats_.camera_rays += l.camera;
        stats_.continuation_rays += l.continuation;
        stats_.shadow_rays += l.shadow_rays;
        stats_.nonfinite_samples += l.nonfinite;
        for (int s = 0; s < STAGES; ++s)
            stats_.stage_seconds[s].second += l.stage_seconds[s];
    }
    stats_.samples_per_pixel += 1;
    stats_.seconds += timer.seconds();
}

std::vector<float> WavefrontCPU::image() {
    std::vector<float> rgb(3 * static_cast<size_t>(pixels_));
    for (int i = 0; i < pixels_; ++i) {
        const float inv = film_[i].w > 0.0f ? 1.0f / film_[i].w : 0.0f;
        rgb[3 * i] = film_[i].x * inv;
        rgb[3 * i + 1] = film_[i].y * inv;
        rgb[3 * i + 2] = film_[i].z * inv;
    }
    return rgb;
}

} // namespace et
