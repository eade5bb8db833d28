// A technique that learns from the render's own first passes, as a pass-level policy: the
// renderer (renderer.h) and the bounce schedule (schedule.h) call it at fixed points -- to set a
// pass's parameters, after each bounce and wave of a learning pass, after each learning pass --
// and name no technique. The visibility strategy's tables are one (visibility_learning.h).
#pragma once
#include "kernels/params.h"
#include "render/schedule.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <memory>

namespace et {

struct DeviceScene;
class Film;

// What a learning technique records during one wave of a learning pass, from path fields read
// between the schedule's launches (StageExecutor::read_fields). One per wave, used on its lane's
// thread only.
class WaveRecorder {
  public:
    virtual ~WaveRecorder() = default;
    // After bounce `bounce`'s shadow rays were traced; counters: that bounce's queue counters.
    virtual void after_bounce(StageExecutor& ex, int bounce, const uint32_t* counters) = 0;
    // After the wave's last bounce, before its film.
    virtual void after_wave(StageExecutor& ex) = 0;
};

// Renders one pass with parameters p into the renderer's pass film, neither kept nor learnt from
// (a technique's measuring pass): the film, or null where a stop request abandoned it.
using MeasuringPass = std::function<const Film*(const etk::EtkParams& p)>;

class LearningPolicy {
  public:
    virtual ~LearningPolicy() = default;
    // Passes 0 .. n-1 are learning passes, rendered in order before any later sample (and
    // learnt from) by every process; n may shrink once the learning ends early.
    virtual int learning_passes() const = 0;
    // Sets pass `sample_index`'s parameters; learn: it is the next learning pass.
    virtual void configure(etk::EtkParams& p, uint32_t sample_index, bool learn) const = 0;
    // The recorder of one wave of n paths of a pass with parameters p; null: nothing to record.
    virtual std::unique_ptr<WaveRecorder> recorder(const etk::EtkParams& p, int n,
                                                   int host_threads) = 0;
    // After learning pass `pass` (sample index `sample_index`, its film whole in `film`,
    // `seconds` of rendering): learn from it, upload what the passes after it use, measure what
    // it needs to with `measure`. False where a measuring pass was abandoned.
    virtual bool after_pass(int pass, uint32_t sample_index, const Film& film, double seconds,
                            WavefrontDevice& device, const MeasuringPass& measure) = 0;
    // Its figures for the render's report: a JSON object.
    virtual nlohmann::json stats() const = 0;
};

// The learning policy of the scene's technique; null where it learns nothing. batches: whether
// the device draws light samples in batches (for the passes it renders with another technique).
std::unique_ptr<LearningPolicy> make_learning_policy(const DeviceScene& scene, bool batches);

} // namespace et
