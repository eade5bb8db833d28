#include "render/schedule.h"

#include "render/light_share.h"
#include "kernels/continuation_guide.h"
#include "render/visibility_cache.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/timer.h"

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

void StageExecutor::read_guide(int, int*, float*, int*, float*) {
    throw Error("this back end cannot read the visibility strategy's records");
}

void StageExecutor::read_paths(int, float*, float*, float*, float*) {
    throw Error("this back end cannot read the continuation guide's path state");
}

void WavefrontDevice::upload_guide(const std::vector<float>&) {
    throw Error("this back end cannot take the visibility strategy's tables");
}

namespace {

// Records (or paths) below this many per thread are handled on one: a thread's start costs more.
constexpr int kMinRecordsPerThread = 16384;

// The threads that n records are handled on, of `threads` at most.
int slices_for(int n, int threads) {
    return std::max(1, std::min(threads, n / kMinRecordsPerThread));
}

// f(k, first, count) for the t slices of n items, on t threads (the calling thread's alone for
// t = 1). VisibilityCache adds in integers, atomically: the tables are the same bits however the
// records are sliced.
template <typename F> void in_slices(int n, int t, F&& f) {
    if (t <= 1) {
        f(0, 0, n);
        return;
    }
    run_on_threads(t, [&](int k) {
        const int a = static_cast<int>(int64_t(n) * k / t);
        f(k, a, static_cast<int>(int64_t(n) * (k + 1) / t) - a);
    });
}

// The continuation guide's records of one wave (visibility_cache.h): each bounce, the paths that
// pushed a continuation from a non-delta vertex note its cell, region, 1 / pdf, the throughput
// after the vertex and the radiance so far; at the wave's end the radiance that came back along
// each continuation is the path's final radiance less that. The paths are scanned, and their
// records added, in slices on the host threads the device leaves free.
class ContinuationRecorder {
  public:
    ContinuationRecorder(int n, int host_threads)
        : n_(n), o_(4 * n), d_(4 * n), b_(4 * n), r_(4 * n),
          vertices_(static_cast<size_t>(slices_for(n, host_threads))) {
        for (auto& v : vertices_) // about two guided vertices per path
            v.reserve(2 * static_cast<size_t>(n) / vertices_.size());
    }

    int slices() const { return static_cast<int>(vertices_.size()); }

    void after_bounce(StageExecutor& ex, int bounce) {
        ex.read_paths(n_, o_.data(), d_.data(), b_.data(), r_.data());
        in_slices(n_, static_cast<int>(vertices_.size()), [&](int k, int first, int count) {
            for (int s = first; s < first + count; ++s) {
                const float* o = &o_[4 * s];
                const float* d = &d_[4 * s];
                const float* b = &b_[4 * s];
                if (static_cast<int>(o[3]) != bounce + 1 || !(d[3] > 0.0f))
                    continue; // no continuation from this bounce's vertex, or a delta one
                Vertex v;
                v.slot = s;
                v.key = static_cast<int>(b[3]) * ETK_GUIDE_REGIONS +
                        etk::etk_cguide_region(etk::make_float3(d[0], d[1], d[2]));
                v.inv_pdf = 1.0f / d[3];
                for (int c = 0; c < 3; ++c) {
                    v.beta[c] = b[c];
                    v.radiance[c] = r_[4 * s + c];
                    v.ray[c] = o[c];
                    v.ray[4 + c] = d[c];
                }
                v.ray[3] = 0.0f;
                v.ray[7] = d[3];
                vertices_[k].push_back(v);
            }
        });
    }

    // After the last bounce: the paths' final radiance, and the records, each slice's on its
    // thread.
    void finish(StageExecutor& ex, VisibilityCache& guide) {
        ex.read_paths(n_, nullptr, nullptr, nullptr, r_.data());
        run_on_threads(static_cast<int>(vertices_.size()), [&](int k) {
            const std::vector<Vertex>& vs = vertices_[k];
            std::vector<int> keys;
            std::vector<float> values, rays;
            keys.reserve(vs.size());
            values.reserve(vs.size());
            rays.reserve(8 * vs.size());
            for (const Vertex& v : vs) {
                float L[3];
                for (int c = 0; c < 3; ++c)
                    L[c] =
                        v.beta[c] > 0.0f ? (r_[4 * v.slot + c] - v.radiance[c]) / v.beta[c] : 0.0f;
                keys.push_back(v.key);
                values.push_back(etk::etk_luma(etk::make_float3(L[0], L[1], L[2])) * v.inv_pdf);
                rays.insert(rays.end(), v.ray, v.ray + 8);
            }
            guide.add_continuations(keys.data(), values.data(), rays.data(),
                                    static_cast<int>(keys.size()));
        });
    }

  private:
    struct Vertex {
        int slot, key;
        float inv_pdf, beta[3], radiance[3];
        float ray[8]; // the continuation's origin, 0, direction, density
    };
    int n_;
    std::vector<float> o_, d_, b_, r_;
    std::vector<std::vector<Vertex>> vertices_; // per slice of the paths
};

} // namespace

RayCounts& RayCounts::operator+=(const RayCounts& o) {
    camera += o.camera;
    continuation += o.continuation;
    shadow += o.shadow;
    shaded += o.shaded;
    nonfinite += o.nonfinite;
    guide_record_seconds += o.guide_record_seconds;
    guide_record_threads = std::max(guide_record_threads, o.guide_record_threads);
    abandoned = abandoned || o.abandoned;
    return *this;
}

bool run_wave(StageExecutor& ex, etk::EtkParams p, int first, int n, RayCounts& counts,
              LightShareLearner* learner, VisibilityCache* guide, int host_threads,
              const StopRequest& stop) {
    p.first_pixel = first;
    std::vector<int> keys;
    std::vector<float> values;
    std::vector<int> exits;
    std::vector<float> parts;
    // A light set sums all its lights at a hit; every other strategy takes one light sample.
    const int shade =
        p.strategy == ETK_STRATEGY_LIGHTS ? etk::ETK_STAGE_shade_lights : etk::ETK_STAGE_shade_hits;
    uint32_t c[etk::ETK_Q_COUNT];
    ex.bind_queues(true); // generate fills queue A
    ex.launch(etk::ETK_STAGE_generate, n, p);
    std::unique_ptr<ContinuationRecorder> recorder;
    if (guide && p.guide_learn && p.guide_continuation) {
        recorder = std::make_unique<ContinuationRecorder>(n, host_threads);
        counts.guide_record_threads = std::max(counts.guide_record_threads, recorder->slices());
    }
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
        if (guide && p.guide_learn && c[etk::ETK_Q_SHADOW] > 0) {
            const Timer t;
            const int m = static_cast<int>(c[etk::ETK_Q_SHADOW]);
            keys.resize(m);
            values.resize(m);
            exits.resize(m);
            parts.resize(2 * static_cast<size_t>(m));
            ex.read_guide(m, keys.data(), values.data(), exits.data(), parts.data());
            const int slices = slices_for(m, host_threads);
            counts.guide_record_threads = std::max(counts.guide_record_threads, slices);
            in_slices(m, slices, [&](int, int a, int k) {
                guide->add(keys.data() + a, values.data() + a, exits.data() + a,
                           parts.data() + 2 * static_cast<size_t>(a), k);
            });
            counts.guide_record_seconds += t.seconds();
        }
        if (recorder && !etk::etk_last_bounce(p, bounce)) { // the last vertex is never guided
            const Timer t;
            recorder->after_bounce(ex, bounce);
            counts.guide_record_seconds += t.seconds();
        }
        rays = static_cast<int>(c[etk::ETK_Q_RAY_OUT]);
        swapped = !swapped;
        if (rays > 0 && stop && stop())
            return false; // the path state is left as it is: the next wave starts afresh
    }
    if (recorder) {
        const Timer t;
        recorder->finish(ex, *guide);
        counts.guide_record_seconds += t.seconds();
    }
    ex.launch(etk::ETK_STAGE_accumulate, n, p);
    ex.read_counters(c); // the last bounce reset them: this is the film's count
    counts.nonfinite += c[etk::ETK_Q_NONFINITE];
    if (learner && p.learn) {
        ex.read_learning(n, learner->bins_of_pass() + first);
    }
    return true;
}

RayCounts run_pass(WavefrontDevice& device, const etk::EtkParams& params,
                   LightShareLearner* learner, VisibilityCache* guide, const StopRequest& stop) {
    const int pixels = params.width * params.height, wave = device.wave_size();
    std::atomic<int> next{0};
    std::atomic<bool> abandoned{false};
    std::vector<RayCounts> counts(device.lanes());
    device.run_lanes([&](int k) {
        for (;;) {
            const int first = next.fetch_add(wave);
            if (first >= pixels)
                break; // (the pass may be whole: no stop asked for once every wave is out)
            if (abandoned.load() || (stop && stop())) {
                abandoned = true;
                break;
            }
            if (!run_wave(device.lane(k), params, first, std::min(wave, pixels - first), counts[k],
                          learner, guide, device.host_threads(), stop)) {
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
