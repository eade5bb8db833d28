// A technique that learns from the render's own first passes, as a pass-level policy: the
// renderer (renderer.h) calls it at fixed points -- to set a pass's parameters, after each
// learning pass -- and names no technique. Its records are made by the stages themselves, on the
// device, and summed there (the visibility strategy's: kernels/visibility_record.h); the policy
// takes the sums between passes. The visibility strategy's tables are one (visibility_learning.h).
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

// Renders one pass with parameters p into the renderer's pass film, neither kept nor learnt from
// (a technique's measuring pass): the film, or null where a stop request abandoned it.
using MeasuringPass = std::function<const Film*(const etk::EtkParams& p)>;

// The samples per pixel a render will take in all, as far as its session knows.
struct LearningPlan {
    int64_t samples = 0; // 0: not known (a noise target; a progressive render, which may go on)
    // A count fixed in advance (a cap, which a resumed render, farm tasks and MPI ranks share):
    // the learning may end before it but never goes on past its usual end, so that a render
    // resumed to more samples renders the same bits as one rendered whole. Not fixed: a time
    // limit's estimate, where a learning may go on as long as the render.
    bool fixed = true;
};

class LearningPolicy {
  public:
    virtual ~LearningPolicy() = default;
    // Passes 0 .. n-1 are learning passes, rendered in order before any later sample (and
    // learnt from) by every process; n may shrink once the learning ends early.
    virtual int learning_passes() const = 0;
    // Sets pass `sample_index`'s parameters; learn: it is the next learning pass.
    virtual void configure(etk::EtkParams& p, uint32_t sample_index, bool learn) const = 0;
    // Whether after_pass reads learning pass `sample_index`'s film (the others' may stay on the
    // device: WavefrontDevice::folds_film).
    virtual bool reads_film(uint32_t sample_index) const = 0;
    // After learning pass `pass` (sample index `sample_index`, its film whole in `film` where
    // reads_film said so, else null; `seconds` of rendering): learn from it, upload what the
    // passes after it use, measure what it needs to with `measure`. False where a measuring pass
    // was abandoned.
    virtual bool after_pass(int pass, uint32_t sample_index, const Film* film, double seconds,
                            WavefrontDevice& device, const MeasuringPass& measure) = 0;
    // The render's plan, given before each after_pass: learning whose tables no later sample
    // would use is skipped.
    virtual void plan(const LearningPlan& plan) { (void)plan; }
    // Its figures for the render's report: a JSON object.
    virtual nlohmann::json stats() const = 0;
};

// The learning policy of the scene's technique; null where it learns nothing. batches: whether
// the device draws light samples in batches (for the passes it renders with another technique).
std::unique_ptr<LearningPolicy> make_learning_policy(const DeviceScene& scene, bool batches);

} // namespace et
