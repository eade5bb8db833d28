#include "render/executor_cpu.h"

#include "util/error.h"
#include "util/parallel.h"
#include "util/timer.h"

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>

namespace et {
namespace {

// Path state and queues start as a device's do: unwritten (default-initialised, not zeroed), so
// a stage that reads a field no earlier stage wrote reads garbage here too, and Valgrind's
// memcheck (tests/portability/memcheck_test.cpp) reports it instead of seeing a zero.
template <typename T> std::unique_ptr<T[]> uninitialised(int n) {
    return std::unique_ptr<T[]>(new T[static_cast<size_t>(n)]);
}

} // namespace

// One thread's wavefront: path state and queues for `wave` paths, expanded from
// kernels/path_state.h.
class CpuDevice::Lane : public StageExecutor {
  public:
    Lane(const DeviceScene& scene, Film& film, int wave)
        : scene_(scene.view()), film_(film.view()), queue_a_(uninitialised<int>(wave)),
          queue_b_(uninitialised<int>(wave)) {
#define ET_LANE_ALLOC(type, name)                                                                  \
    name##_ = uninitialised<type>(wave);                                                           \
    paths_.name = name##_.get();
        ETK_PATH_FIELDS(ET_LANE_ALLOC)
#undef ET_LANE_ALLOC
#define ET_QUEUE_ALLOC(name)                                                                       \
    name##_ = uninitialised<int>(wave);                                                            \
    queues_.name = name##_.get();
        ETK_FIXED_QUEUES(ET_QUEUE_ALLOC)
#undef ET_QUEUE_ALLOC
        queues_.counters = counters_;
    }

    void bind_queues(bool swapped) override {
        queues_.ray_in = swapped ? queue_b_.get() : queue_a_.get();
        queues_.ray_out = swapped ? queue_a_.get() : queue_b_.get();
    }
    void reset_counters() override {
        std::fill(counters_, counters_ + etk::ETK_Q_COUNT, 0u);
    }
    void read_counters(uint32_t* out) override {
        std::copy(counters_, counters_ + etk::ETK_Q_COUNT, out);
    }
    void read_fields(int n, const std::vector<FieldRead>& reads) override {
        for (const FieldRead& r : reads)
            std::memcpy(r.to, field(r.field), path_field_bytes(r.field) * static_cast<size_t>(n));
    }
    // The cells' tables live in the device, not the (read-only) prepared scene; the record sums
    // are the device's, shared by the lanes.
    void set_guide(const float* cells, uint32_t* sums) {
        scene_.guide_cells = cells;
        queues_.guide_sums = sums;
    }

    void launch(int stage, int n, const etk::EtkParams& p) override {
        if (n <= 0)
            return;
        Timer t;
        const etk::EtkScene S = scene_;
        const etk::EtkPaths P = paths_;
        const etk::EtkQueues Q = queues_;
        const etk::EtkFilm F = film_;
        switch (stage) { // one loop per stage, so each stage function inlines into its loop
#define ET_STAGE_CASE(kernel, fn, pushes)                                                          \
    case etk::ETK_STAGE_##kernel:                                                                  \
        for (int i = 0; i < n; ++i) {                                                              \
            etk::EtkPushes out = etk::etk_no_pushes();                                             \
            etk::fn(S, P, Q, F, p, i, &out);                                                       \
            etk::etk_push_each(Q, &out);                                                           \
        }                                                                                          \
        break;
            ETK_STAGES(ET_STAGE_CASE)
#undef ET_STAGE_CASE
        }
        seconds[stage] += t.seconds();
    }

    double seconds[etk::ETK_STAGE_COUNT] = {};

  private:
    const void* field(int f) const {
        switch (f) {
#define ET_FIELD_CASE(type, name)                                                                  \
    case etk::ETK_FIELD_##name:                                                                    \
        return name##_.get();
            ETK_PATH_FIELDS(ET_FIELD_CASE)
#undef ET_FIELD_CASE
        }
        throw Error("no path field " + std::to_string(f) + " (a bug)");
    }
    etk::EtkScene scene_;
    etk::EtkFilm film_;
    etk::EtkPaths paths_{};
    etk::EtkQueues queues_{};
#define ET_LANE_ARRAY(type, name) std::unique_ptr<type[]> name##_;
    ETK_PATH_FIELDS(ET_LANE_ARRAY)
#undef ET_LANE_ARRAY
    std::unique_ptr<int[]> queue_a_, queue_b_;
#define ET_QUEUE_ARRAY(name) std::unique_ptr<int[]> name##_;
    ETK_FIXED_QUEUES(ET_QUEUE_ARRAY)
#undef ET_QUEUE_ARRAY
    uint32_t counters_[etk::ETK_Q_COUNT] = {};
};

CpuDevice::CpuDevice(const DeviceScene& scene, Film& film, int threads, int wave)
    : guide_cells_(scene.guide_cells), guide_sums_(std::max<size_t>(1, scene.guide_sum_words()), 0),
      film_(film), wave_(wave > 0 ? wave : 1024) {
    const int n = thread_count(threads);
    for (int t = 0; t < n; ++t) {
        lanes_.push_back(std::make_unique<Lane>(scene, film, wave_));
        lanes_.back()->set_guide(guide_cells_.data(), guide_sums_.data());
    }
}

void CpuDevice::clear_film(bool aovs) {
#define ET_CLEAR(type, name)                                                                       \
    if (aovs || !film_field_is_aov(etk::ETK_ARG_##name))                                           \
        std::fill(film_.name.begin(), film_.name.end(), type{});
    ETK_FILM_FIELDS(ET_CLEAR)
#undef ET_CLEAR
}

void CpuDevice::upload_guide(const std::vector<float>& cells,
                             const std::vector<FloatSpan>& changed) {
    // The learned tables are the buffer's first floats (the binned technique's may follow).
    if (cells.size() > guide_cells_.size())
        throw Error("visibility tables of " + std::to_string(cells.size()) + " floats, more than " +
                    std::to_string(guide_cells_.size()));
    // Between passes: no reader.
    copy_spans(cells.data(), cells.size(), changed, guide_cells_.data());
}

void CpuDevice::absorb_guide_sums(const GuideSumsAbsorb& absorb) {
    // Between passes: no lane adds; the lanes keep their pointers.
    absorb(guide_sums_.data(), guide_sums_.size());
}

CpuDevice::~CpuDevice() = default;

int CpuDevice::lanes() const {
    return static_cast<int>(lanes_.size());
}

StageExecutor& CpuDevice::lane(int k) {
    return *lanes_[k];
}

void CpuDevice::run_lanes(const std::function<void(int)>& f) {
    run_on_threads(lanes(), f);
}

std::vector<std::pair<std::string, double>> CpuDevice::stage_seconds() {
    std::vector<std::pair<std::string, double>> out;
    for (int s = 0; s < etk::ETK_STAGE_COUNT; ++s) {
        double t = 0.0;
        for (const auto& l : lanes_)
            t += l->seconds[s];
        out.emplace_back(stage_name(s), t);
    }
    return out;
}

} // namespace et
