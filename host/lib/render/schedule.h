// The bounce schedule, written once: generate -> (closest hit, lighting escaped rays -> shade ->
// shadow rays) per bounce while rays remain -> film. It drives a StageExecutor, which the OpenCL
// and the native back ends implement (executor_cl.h, executor_cpu.h), the way pbrt-v4's wavefront
// integrator drives its per-device launches.
#pragma once
#include "kernels/params.h"
#include "kernels/path_state.h"
#include "util/float_span.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace et {

class FilmSums;

// The stage names (the OpenCL kernel names), indexed by ETK_STAGE_*.
const char* stage_name(int stage);

// One path field to read: ETK_FIELD_* and where its elements go.
struct FieldRead {
    int field;
    void* to;
};
// Bytes per element of path field `field` (ETK_FIELD_*).
size_t path_field_bytes(int field);

// Runs the stages over a set of paths in flight: path state, queues and counters of its own.
class StageExecutor {
  public:
    virtual ~StageExecutor() = default;
    // ray_in/ray_out are queue buffers A/B, or B/A when swapped.
    virtual void bind_queues(bool swapped) = 0;
    virtual void reset_counters() = 0;
    virtual void read_counters(uint32_t counters[etk::ETK_Q_COUNT]) = 0;
    // Runs `stage` over entries 0 .. n-1 of its queue (nothing when n <= 0).
    virtual void launch(int stage, int n, const etk::EtkParams& params) = 0;
    // A wave counted on the device (run_wave): whether this executor counts so, the counters'
    // step between two bounces (kernels/integrator.h, etk_next_bounce; first_rays >= 0: before
    // the first), and a launch of `stage` over as many entries of its queue as its counter
    // holds, at most `most` (the host's launch size).
    virtual bool counts_on_device() const { return false; }
    virtual void next_bounce(int first_rays);
    virtual void launch_counted(int stage, int most, const etk::EtkParams& params);
    // The first n elements of path fields (ETK_FIELD_*), each into its `to` (elements of the
    // field's type, path_field_bytes apiece): what a learning technique reads between launches.
    virtual void read_fields(int n, const std::vector<FieldRead>& reads) = 0;
};

struct RayCounts {
    uint64_t camera = 0, continuation = 0, shadow = 0;
    uint64_t shaded = 0;    // surface hits shaded (one light sample or light-set sum each)
    uint64_t nonfinite = 0; // samples dropped by the film; anything but 0 is a bug
    bool abandoned = false; // a stop request ended the pass early: its film is incomplete
    RayCounts& operator+=(const RayCounts& o);
};

class Film;

// A back end: one or more executors ("lanes") that can run waves concurrently, and the film.
class WavefrontDevice {
  public:
    virtual ~WavefrontDevice() = default;
    virtual std::string name() const = 0;
    virtual int lanes() const = 0;
    virtual int wave_size() const = 0; // paths in flight per lane
    virtual StageExecutor& lane(int k) = 0;
    // Runs f(k) for every lane k, concurrently where the device can.
    virtual void run_lanes(const std::function<void(int)>& f) = 0;
    virtual void finish() = 0; // waits until the pass is done
    // A pass renders into a zeroed film: the device zeroes its own copy (clear_film) and hands
    // the pass back (download_film): no-ops where the device writes the host's film. With
    // aovs false the AOV fields may be left as they are: nobody reads them.
    virtual void clear_film(bool aovs) = 0;
    virtual void download_film(Film& film, bool aovs) = 0;
    // Time per stage so far: summed over the lanes, device time for OpenCL (kernels of several
    // lanes may overlap), thread time natively.
    virtual std::vector<std::pair<std::string, double>> stage_seconds() = 0;
    // A learning technique's tables (EtkScene.guide_cells) for the passes to come: `cells`, of
    // which only the spans `changed` (floats [first, second)) differ from the tables uploaded
    // before -- natively and on an OpenCL device sharing the host's memory only those are copied
    // (a few of tens of megabytes); any other OpenCL device is written all.
    virtual void upload_guide(const std::vector<float>& cells,
                              const std::vector<FloatSpan>& changed);
    // Hands the visibility records' sums the stages added since the last call (DeviceScene::
    // guide_sum_words words, kernels/visibility_record.h) to `absorb`, between passes, which
    // leaves them zero for the passes to come: natively the device's own words (no copy, and no
    // second buffer of tens of megabytes), from an OpenCL device that shares the host's memory
    // its buffer mapped in place, from any other a copy (the device then zeroes its buffer).
    using GuideSumsAbsorb = std::function<void(uint32_t* words, size_t count)>;
    virtual void absorb_guide_sums(const GuideSumsAbsorb& absorb);
    // Whether LightBatch::automatic draws light samples in batches here (a CPU: yes).
    virtual bool prefers_light_batches() const { return true; }
    // Whether the device keeps the film's exact sums itself (FilmSumsAt): then fold_film adds
    // the pass just rendered to them (after finish(), in place of the host's FilmSums::add_pass;
    // the film is read back only where someone reads it), and take_film_sums adds them, exactly,
    // to `sums` and starts them again from zero.
    virtual bool folds_film() const { return false; }
    virtual void fold_film();
    virtual void take_film_sums(FilmSums& sums);
};

// Asked between waves and between bounces (from any lane's thread): true abandons the pass in
// flight, whose film is then incomplete and must not be kept. A pass of a deep scene can take
// minutes; a signal or a time limit should not wait for it. Empty: never asked.
using StopRequest = std::function<bool()>;

// One wave: paths for pixels first, first + s ... first + (n - 1) s (s = params.pixel_stride, 1
// where it is 0), sample params.sample_index, all bounces, into the film. Adds the rays traced to
// `counts`. Returns false where `stop` ended the wave before its film was written.
bool run_wave(StageExecutor& ex, etk::EtkParams params, int first, int n, RayCounts& counts,
              const StopRequest& stop = {});

// Hands a pass's paths out to the lanes as waves (any thread may ask). Path k of the pass is
// pixel k x stride. Where each lane takes several waves, waves of `wave` paths, and towards the
// pass's end a share of what is left, so that the lanes finish together: a lane that ran out while
// another still had a whole wave to go would idle meanwhile, and a CPU device's lane is a compute
// unit of its own (executor_cl.h, one_unit_sub_devices) with large waves. Shares are never below
// kTailWave paths (only the pass's last wave, and a device's smaller waves, may be). A pass of at
// most one wave a lane (a small film) on at most kMostInterleaved lanes is dealt path by path
// instead, lane k's wave every lanes-th path from path k, so each has an even share of the image's
// costly and cheap parts without more launches (on more lanes neighbouring paths would lie far
// apart: measured on two). One lane (a GPU's) takes whole waves. Every path is dealt once.
class WaveDealer {
  public:
    struct Wave {
        int first_pixel, pixel_stride, n; // run_wave's first pixel, params.pixel_stride and n
    };
    static constexpr int kTailWave = 4096;
    static constexpr int kMostInterleaved = 4;

    WaveDealer(int paths, int stride, int wave, int lanes);
    // The next wave, or false when the pass is handed out.
    bool next(Wave* w);

  private:
    int wave_size_for(int left) const;

    const int paths_, stride_, wave_, lanes_;
    const bool interleaved_;
    std::atomic<int> next_{0}; // interleaved: the next lane's share; else the next path
};

// One pass: sample params.sample_index of every pixel (of every params.pixel_stride-th: a
// measuring pass's subset, the others left as they are), in waves of at most the device's size
// that a WaveDealer hands to its lanes as they free up. `stop` may abandon it (the result's
// `abandoned`); the waiting lanes then take no more waves.
RayCounts run_pass(WavefrontDevice& device, const etk::EtkParams& params,
                   const StopRequest& stop = {});

} // namespace et
