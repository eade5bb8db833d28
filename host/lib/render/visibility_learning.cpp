#include "render/visibility_learning.h"

#include "kernels/continuation_guide.h"
#include "prepare/device_scene.h"
#include "prepare/technique.h"
#include "render/film.h"
#include "util/parallel.h"
#include "util/timer.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace et {

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
        : n_(n), o_(4 * n), d_(4 * n), b_(4 * n), r_(4 * n), depth_(n), cell_(n), pdf_(n),
          vertices_(static_cast<size_t>(slices_for(n, host_threads))) {
        for (auto& v : vertices_) // about two guided vertices per path
            v.reserve(2 * static_cast<size_t>(n) / vertices_.size());
    }

    int slices() const { return static_cast<int>(vertices_.size()); }

    void after_bounce(StageExecutor& ex, int bounce) {
        ex.read_fields(n_, {{etk::ETK_FIELD_ray_o, o_.data()},
                            {etk::ETK_FIELD_ray_d, d_.data()},
                            {etk::ETK_FIELD_beta, b_.data()},
                            {etk::ETK_FIELD_radiance, r_.data()},
                            {etk::ETK_FIELD_depth, depth_.data()},
                            {etk::ETK_FIELD_ray_pdf, pdf_.data()},
                            {etk::ETK_FIELD_ray_cell, cell_.data()}});
        in_slices(n_, static_cast<int>(vertices_.size()), [&](int k, int first, int count) {
            for (int s = first; s < first + count; ++s) {
                const float* o = &o_[4 * s];
                const float* d = &d_[4 * s];
                const float* b = &b_[4 * s];
                if (depth_[s] != bounce + 1 || !(pdf_[s] > 0.0f))
                    continue; // no continuation from this bounce's vertex, or a delta one
                Vertex v;
                v.slot = s;
                v.key = cell_[s] * ETK_GUIDE_REGIONS +
                        etk::etk_cguide_region(etk::make_float3(d[0], d[1], d[2]));
                v.inv_pdf = 1.0f / pdf_[s];
                for (int c = 0; c < 3; ++c) {
                    v.beta[c] = b[c];
                    v.radiance[c] = r_[4 * s + c];
                    v.ray[c] = o[c];
                    v.ray[4 + c] = d[c];
                }
                v.ray[3] = 0.0f;
                v.ray[7] = pdf_[s];
                vertices_[k].push_back(v);
            }
        });
    }

    // After the last bounce: the paths' final radiance, and the records, each slice's on its
    // thread.
    void finish(StageExecutor& ex, VisibilityCache& guide) {
        ex.read_fields(n_, {{etk::ETK_FIELD_radiance, r_.data()}});
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
    std::vector<int> depth_, cell_;
    std::vector<float> pdf_;
    std::vector<std::vector<Vertex>> vertices_; // per slice of the paths
};

// One wave's continuation records of a learning pass, read and added on the host (the shadow rays'
// records are summed on the device: kernels/visibility_record.h).
class VisibilityRecorder : public WaveRecorder {
  public:
    VisibilityRecorder(VisibilityLearning& policy, VisibilityCache& cache, const etk::EtkParams& p,
                       int n, int host_threads)
        : policy_(policy), cache_(cache), p_(p), continuations_(n, host_threads) {}
    ~VisibilityRecorder() override { policy_.add_record_time(seconds_, continuations_.slices()); }

    void after_bounce(StageExecutor& ex, int bounce, const uint32_t*) override {
        if (etk::etk_last_bounce(p_, bounce)) // the last vertex: never guided
            return;
        const Timer t;
        continuations_.after_bounce(ex, bounce);
        seconds_ += t.seconds();
    }
    void after_wave(StageExecutor& ex) override {
        const Timer t;
        continuations_.finish(ex, cache_);
        seconds_ += t.seconds();
    }

  private:
    VisibilityLearning& policy_;
    VisibilityCache& cache_;
    etk::EtkParams p_;
    double seconds_ = 0.0;
    ContinuationRecorder continuations_;
};

} // namespace

VisibilityLearning::VisibilityLearning(const DeviceScene& scene, bool batches)
    : scene_(scene), options_(scene.guide_options) {
    etk::EtkParams fallback = scene.params;
    set_technique(fallback, options_.fallback);
    fallback_light_batch_ = technique_batches_light_samples(fallback) && batches;
    options_.continuation = scene.params.guide_continuation != 0;
    std::array<float, 6> box;
    const float* table = scene.guide_cells.data() +
                         etk::etk_portal_offset(options_.slots, options_.continuation ? 1 : 0);
    std::copy(table, table + 6, box.begin());
    cache_ = std::make_unique<VisibilityCache>(options_, scene.guide_regions, scene.guide_map_power,
                                               box);
    host_bytes_ = cache_->bytes();
    device_bytes_ = (scene.guide_cells.size() + scene.guide_regions.size()) * sizeof(float) +
                    scene.guide_sum_words() * sizeof(uint32_t);
}

int VisibilityLearning::verdict_start() const {
    return std::min(options_.learning_passes, options_.verdict_after);
}

int VisibilityLearning::learning_passes() const {
    // The passes the tables learn from and the verdict's; a verdict for the fallback ends the
    // learning.
    const int verdict_end =
        options_.verdict_passes > 0 ? verdict_start() + options_.verdict_passes : 0;
    return dropped_ ? verdict_end : std::max(options_.learning_passes, verdict_end);
}

bool VisibilityLearning::fallback_pass(uint32_t sample_index) const {
    return sample_index >= kVerdictFallbackBase || dropped_;
}

bool VisibilityLearning::learns_tables(uint32_t sample_index) const {
    return !fallback_pass(sample_index) && sample_index < uint32_t(options_.learning_passes);
}

void VisibilityLearning::configure(etk::EtkParams& p, uint32_t sample_index, bool learn) const {
    p.guide_ready = ready_ ? 1 : 0;
    // The verdict's measuring passes and, after a verdict for it, every pass: the fallback
    // estimator, with the strategy's MIS heuristic and GGX sampling.
    if (fallback_pass(sample_index)) {
        set_technique(p, options_.fallback);
        p.light_batch = fallback_light_batch_ ? 1 : 0;
        p.guide_ready = 0;
    }
    p.guide_learn = learn && learns_tables(sample_index) ? 1 : 0;
}

std::unique_ptr<WaveRecorder> VisibilityLearning::recorder(const etk::EtkParams& p, int n,
                                                           int host_threads) {
    if (!p.guide_learn || !p.guide_continuation || !cache_)
        return nullptr;
    return std::make_unique<VisibilityRecorder>(*this, *cache_, p, n, host_threads);
}

void VisibilityLearning::add_record_time(double seconds, int threads) {
    const std::lock_guard<std::mutex> lock(mutex_);
    record_seconds_ += seconds;
    record_threads_ = std::max(record_threads_, threads);
}

void VisibilityLearning::update_tables(int pass, WavefrontDevice& device) {
    // Rebuilt after passes 1, 2, 4, ... L.
    if (VisibilityCache::update_after(pass, options_.learning_passes)) {
        const Timer t;
        device.take_guide_sums(sums_);
        cache_->absorb(sums_);
        device.upload_guide(cache_->tables());
        ready_ = true;
        light_counts_ = cache_->fewer_light_samples();
        update_seconds_ += t.seconds();
    }
    records_ = cache_->records();
    continuation_records_ = cache_->continuation_records();
}

bool VisibilityLearning::after_pass(int pass, uint32_t sample_index, const Film& film,
                                    double seconds, WavefrontDevice& device,
                                    const MeasuringPass& measure) {
    if (learns_tables(sample_index) && cache_) {
        const Timer t;
        update_tables(pass, device);
        learning_seconds_ += seconds + t.seconds();
        if (pass + 1 == options_.learning_passes)
            cache_.reset(); // learned: the sums are no longer needed
    }
    const int64_t verdict_pass = int64_t(sample_index) - verdict_start();
    if (verdict_pass < 0 || verdict_pass >= options_.verdict_passes)
        return true;
    // The verdict's passes of the tables, then the fallback's, then the choice.
    if (!verdict_)
        verdict_ = std::make_unique<GuideVerdict>(
            film.width(), film.height(), options_.verdict_passes,
            verdict_cost_for(options_, scene_.params.guide_continuation != 0));
    verdict_->add(1, static_cast<int>(verdict_pass), &film.film_sum[0].x);
    if (verdict_pass + 1 < options_.verdict_passes)
        return true;
    const Timer t;
    const bool whole = give_verdict(measure);
    verdict_seconds_ += t.seconds();
    if (dropped_)
        cache_.reset(); // no more learning
    return whole;
}

bool VisibilityLearning::give_verdict(const MeasuringPass& measure) {
    for (int k = 0; k < options_.verdict_passes; ++k) {
        etk::EtkParams p = scene_.params;
        p.sample_index = kVerdictFallbackBase + static_cast<uint32_t>(k);
        configure(p, p.sample_index, false);
        const Film* film = measure(p);
        if (!film)
            return false;
        verdict_->add(0, k, &film->film_sum[0].x);
    }
    dropped_ = !verdict_->tables_win();
    chosen_ = dropped_ ? 0 : 1;
    verdict_fallback_error_ = verdict_->fallback_error();
    verdict_tables_error_ = verdict_->tables_error();
    verdict_.reset();
    return true;
}

nlohmann::json VisibilityLearning::stats() const {
    nlohmann::json counts = nlohmann::json::object();
    for (const auto& [n, cells] : light_counts_)
        counts[nlohmann::json(n).dump()] = cells; // keys "0.5", "0.25", "0.125"
    const std::lock_guard<std::mutex> lock(mutex_);
    return {{"learning_passes", options_.learning_passes},
            {"learning_seconds", learning_seconds_},
            {"update_seconds", update_seconds_},
            {"record_seconds", record_seconds_},
            {"record_threads", record_threads_},
            {"records", records_},
            {"continuation_records", continuation_records_},
            {"host_bytes", host_bytes_},
            {"device_bytes", device_bytes_},
            {"cells_with_fewer_light_samples", counts},
            {"verdict", chosen_ < 0 ? "none"
                        : chosen_   ? "tables"
                                    : name_of(options_.fallback)},
            {"verdict_passes", options_.verdict_passes},
            {"verdict_cost", verdict_cost_for(options_, scene_.params.guide_continuation != 0)},
            {"verdict_seconds", verdict_seconds_},
            {"verdict_fallback_error", verdict_fallback_error_},
            {"verdict_tables_error", verdict_tables_error_}};
}

} // namespace et
