#include "session/progressive_render.h"

#include <utility>

namespace et {

ProgressiveRender::ProgressiveRender(const Cluster& cluster, Scene scene,
                                     const RenderSettings& settings, std::string name)
    : cluster_(cluster), name_(std::move(name)) {
    prepared_ = prepare_render(std::move(scene), settings);
    new_session(RenderState{});
}

// A session continuing `resumed` (empty: a new film) from its sample count on.
void ProgressiveRender::new_session(RenderState resumed) {
    SessionOptions o;
    o.scene = name_;
    o.resume = resumed.spp > 0;
    o.open_ended = true;
    session_ = std::make_unique<RenderSession>(cluster_, *prepared_, o, &build_);
    session_->resume(std::move(resumed));
    session_->start();
}

const SessionResult& ProgressiveRender::render_to(int spp, const SessionCallbacks& callbacks) {
    if (session_->abandoned())
        new_session(session_->state_of(result_.sums));
    if (spp <= session_->done() && result_.spp > 0)
        return result_;
    session_->extend(spp);
    const int before = result_.spp;
    result_ = session_->run(callbacks);
    // The report is of this call (its seconds are): the film went on from `before` samples.
    result_.resumed_from = before;
    return result_;
}

RenderReport ProgressiveRender::report() const {
    return render_report({*session_, result_, build_, cluster_.size()});
}

} // namespace et
