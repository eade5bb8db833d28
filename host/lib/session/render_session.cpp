#include "session/render_session.h"

#include "render/noise_estimate.h"
#include "util/interrupt.h"

#include <xxhash.h>

#include <algorithm>
#include <cstdio>
#include <limits>

namespace et {

bool uncapped_render(const SessionOptions& o, const RenderSettings& st) {
    return !o.partial && (st.time_limit > 0 || o.noise_target > 0) && o.spp <= 0;
}

RenderSession::RenderSession(const Cluster& cluster, const PreparedRender& prepared,
                             SessionOptions options, ProgramBuildInfo* build)
    : cluster_(cluster), prepared_(prepared), options_(std::move(options)) {
    key_ = render_key(prepared_.scene);
    renderer_ = make_renderer(prepared_.scene, build);
    first_ = options_.partial ? options_.first : 0;
    end_ = options_.partial                        ? options_.end
           : uncapped_render(options_, settings()) ? int64_t(1) << 24
                                                   : settings().spp;
}

int RenderSession::whole_render() const {
    if (options_.partial)
        return options_.spp > 0 ? options_.spp : options_.end;
    return uncapped_render(options_, settings()) ? 0 : static_cast<int>(end_);
}

RenderState RenderSession::state_of(FilmSums sums) const {
    return RenderState{key_, static_cast<int>(done_), static_cast<int>(first_), std::move(sums),
                       whole_render()};
}

// The ranks must render one film: the same scene, inputs and settings everywhere.
void RenderSession::agree_on_key() const {
    const uint64_t root_key = static_cast<uint64_t>(cluster_.broadcast(static_cast<int64_t>(key_)));
    cluster_.check(root_key == key_
                       ? ""
                       : options_.scene +
                             ": the scene, its inputs, the settings or envtrace differ from rank "
                             "0's (render key " +
                             std::to_string(key_) + ", rank 0 has " + std::to_string(root_key) +
                             "): the ranks would not render one film");
}

// And how many samples, which and until when: options outside the render key, which ranks
// started with different command lines (MPMD) could disagree on, rendering a wrong film or
// ending in an MPI error without a word.
void RenderSession::agree_on_samples() const {
    const SessionOptions& o = options_;
    char limits[96];
    std::snprintf(limits, sizeof limits, ", time limit %g, noise target %g", settings().time_limit,
                  o.noise_target);
    const int range_end = o.partial ? o.end : 0;
    const std::string control = "range " + std::to_string(first_) + ":" +
                                std::to_string(range_end) + ", spp " +
                                std::to_string(settings().spp) + (o.spp > 0 ? " (--spp)" : "") +
                                limits + (o.resume ? ", resumed" : "");
    const uint64_t mine = XXH3_64bits(control.data(), control.size());
    const uint64_t root = static_cast<uint64_t>(cluster_.broadcast(static_cast<int64_t>(mine)));
    cluster_.check(root == mine ? ""
                                : o.scene + ": this rank's samples (" + control +
                                      ") differ from rank 0's: --spp, --sample-range, "
                                      "--time-limit, --noise-target and --resume must be the "
                                      "same on every rank");
}

void RenderSession::start() {
    agree_on_key();
    agree_on_samples();
    done_ = cluster_.broadcast(resumed_.spp);
    if (options_.resume && cluster_.root())
        renderer_->resume(resumed_.sums);
    resumed_.sums = FilmSums();
    resumed_from_ = done_;
}

void RenderSession::extend(int64_t end) {
    if (options_.partial || cluster_.size() > 1)
        throw Error(options_.scene + ": only a whole render of one process renders on");
    if (stopped_)
        throw Error(options_.scene + ": a stop abandoned a pass: this session renders no more");
    end_ = std::max(end, first_ + done_);
    stop_request_ = 0;
    signal_ = 0;
    noise_reached_ = false;
}

int RenderSession::stop_signal() const {
    const int caught = InterruptHandler::signal();
    return caught ? caught : stop_request_.load();
}

// The time limit abandons no round before this run's first is whole: a resumed render whose
// first round (learning passes replayed included) outlasts the limit would otherwise drop it
// every time, and a loop of time-limited resumes never get further.
bool RenderSession::time_up() const {
    return settings().time_limit > 0 && done_ > resumed_from_ &&
           render_.seconds() >= settings().time_limit;
}

// The noise target is checked on the summed film (every rank's, reduced to rank 0) at spp counts
// every rank knows (kNoiseFirstCheck, then where the error is predicted to meet the target, at
// most doubling), so that the few reductions cost little.
void RenderSession::check_noise(const SessionCallbacks& cb) {
    const FilmSums all = cluster_.reduce(renderer_->sums());
    const double target = options_.noise_target;
    int64_t next = next_check_, reached = 0;
    if (cluster_.root()) {
        noise_error_ = relative_error(all);
        reached = noise_error_ <= target;
        next = next_noise_check(done_, noise_error_, target);
        char line[160];
        std::snprintf(line, sizeof line,
                      "noise check at %lld spp: estimated relative error %.4g (target %g)",
                      static_cast<long long>(done_), noise_error_, target);
        if (cb.note)
            cb.note(line + (reached ? "" : ", next check at " + std::to_string(next) + " spp"));
    }
    noise_reached_ = cluster_.broadcast(reached) != 0;
    next_check_ = cluster_.broadcast(next);
    if (options_.spp <= 0 && cb.progress_total)
        cb.progress_total(static_cast<int>(std::min(end_, next_check_)));
}

// The samples the render will take in all, for a learning technique (Renderer::set_plan): the
// count where one caps it -- the whole render's for a farm task, so that every task learns alike
// -- and, for one process under a time limit that ends it sooner, what the rate so far leaves
// room for (the learning passes it is asked after are the slower ones: an estimate on the short
// side). Not known for a progressive render, which may be extended (RenderSession::extend), a
// noise target alone, or under a time limit on MPI ranks, whose clocks would disagree.
LearningPlan RenderSession::learning_plan() const {
    if (options_.open_ended)
        return {};
    if (options_.partial)
        return {whole_render(), true};
    const int64_t capped = uncapped_render(options_, settings()) ? 0 : end_;
    const double limit = settings().time_limit, t = render_.seconds();
    if (limit <= 0 || cluster_.size() > 1 || !(t > 0))
        return {capped, true};
    const int64_t passes = done_ - resumed_from_ + 1; // this run's, the one just rendered included
    const int64_t timed = done_ + 1 + int64_t(std::max(0.0, limit - t) * double(passes) / t);
    if (capped > 0 && capped <= timed)
        return {capped, true};
    return {timed, false};
}

// What the ranks agree on before each round: stop (a signal on any rank, the time limit by rank
// 0's clock, or the range done), save a checkpoint (rank 0's clock), a failure.
RenderSession::RoundVerdict RenderSession::agree_round() {
    int64_t f[4] = {0, 0, render_error_.empty() ? 0 : 1, stop_signal()};
    if (f[3] != 0 || stopped_ || (done_ > 0 && first_ + done_ >= end_) || noise_reached_ ||
        (cluster_.root() && time_up()))
        f[0] = 1;
    if (cluster_.root() && options_.checkpoint >= 0 && done_ > resumed_from_ &&
        since_checkpoint_.seconds() >= options_.checkpoint)
        f[1] = 1;
    cluster_.max_all(f, 4);
    if (f[2])
        cluster_.check(render_error_);
    signal_ = static_cast<int>(f[3]);
    return {f[0] != 0, f[1] != 0};
}

void RenderSession::save_checkpoint() {
    const FilmSums all = cluster_.reduce(renderer_->sums());
    cluster_.check(attempt([&] {
        if (cluster_.root())
            write_render_state(options_.state_path, state_of(all));
    }));
    since_checkpoint_ = Timer();
}

// MPI ranks keep a round only where no rank abandoned its part (a film of whole rounds).
void RenderSession::render_round(const SessionCallbacks& cb) {
    const int64_t index = first_ + done_ + cluster_.rank();
    bool whole = true;
    if (index < end_)
        render_error_ =
            attempt([&] { whole = renderer_->render_sample(static_cast<uint32_t>(index)); });
    if (cluster_.size() > 1) {
        int64_t g[2] = {whole ? 0 : 1, renderer_->abandoned() ? 1 : 0};
        cluster_.max_all(g, 2);
        whole = g[0] == 0;
        stopped_ = g[1] != 0;
        if (whole)
            renderer_->keep_held();
        else
            renderer_->drop_held();
    } else {
        stopped_ = renderer_->abandoned();
    }
    if (!whole)
        return; // the next agreement stops, with the rounds before this one
    done_ += std::min<int64_t>(cluster_.size(), end_ - (first_ + done_));
    if (cluster_.root() && cb.progress)
        cb.progress(static_cast<int>(done_), render_.seconds());
}

SessionResult RenderSession::run(const SessionCallbacks& cb) {
    renderer_->set_stop([this] { return done_ > 0 && (stop_signal() != 0 || time_up()); });
    renderer_->set_plan([this] { return learning_plan(); });
    renderer_->set_hold(cluster_.size() > 1);
    noise_error_ = std::numeric_limits<double>::infinity();
    next_check_ = std::max<int64_t>(kNoiseFirstCheck, done_);
    const bool noise = options_.noise_target > 0;
    if (noise && options_.spp <= 0 && cb.progress_total)
        cb.progress_total(static_cast<int>(std::min(end_, next_check_)));
    render_ = since_checkpoint_ = Timer();
    for (;;) {
        if (noise && !noise_reached_ && !stopped_ && done_ >= next_check_ && first_ + done_ < end_)
            check_noise(cb);
        const RoundVerdict v = agree_round();
        if (v.stop)
            break;
        if (v.checkpoint)
            save_checkpoint();
        render_round(cb);
    }
    return finish();
}

// The film of every rank, summed on rank 0 (exactly: in any order), and the rays they traced.
SessionResult RenderSession::finish() {
    SessionResult r;
    r.render_seconds = render_.seconds();
    r.sums = cluster_.reduce(renderer_->sums());
    r.stats = renderer_->stats();
    uint64_t counts[5] = {r.stats.camera_rays, r.stats.continuation_rays, r.stats.shadow_rays,
                          r.stats.nonfinite_samples, r.stats.shaded_hits};
    cluster_.sum_to_root(counts, 5);
    r.stats.camera_rays = counts[0];
    r.stats.continuation_rays = counts[1];
    r.stats.shadow_rays = counts[2];
    r.stats.nonfinite_samples = counts[3];
    r.stats.shaded_hits = counts[4];
    r.spp = static_cast<int>(done_);
    r.first = static_cast<int>(first_);
    r.resumed_from = static_cast<int>(resumed_from_);
    r.signal = signal_;
    r.stopped = stopped_;
    r.noise_reached = noise_reached_;
    r.noise_error = noise_error_;
    if (cluster_.root() && !options_.partial) // of the image written
        r.noise_error = relative_error(r.sums);
    return r;
}

} // namespace et
