// One render of a prepared scene, from its first sample to a stop rule: the library's render
// loop, which the command line (and any other front end) drives.
//
// Sample indices first .. end-1; done() of them are in the film (on rank 0: a resumed state's
// count too). In each round, rank r renders index first + done + r: the ranks take disjoint
// indices, and a round ends with the film holding a prefix of the range, which an interrupted or
// time-limited render writes and a resumed one continues, with any number of ranks.
//
// A render stops when, before a round, any of these holds: the range is done; a stop was asked
// for (a signal caught by an InterruptHandler, or request_stop); the time limit has passed; the
// noise target is met; a round was abandoned. A stop request or the time limit abandons the round
// in flight between two bounces (a pass of a deep scene can take minutes), keeping the rounds
// before it; the first round is always finished, so that there is an image of one sample.
#pragma once
#include "render/film_sums.h"
#include "render/render_state.h"
#include "render/renderer.h"
#include "session/cluster.h"
#include "session/prepared_render.h"
#include "util/timer.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace et {

// What a session renders beyond the scene's settings: which samples, until when, what it keeps.
struct SessionOptions {
    std::string scene; // the scene file, as messages name it
    // Samples per pixel the user asked for (0: none, the settings' spp applies). It caps a
    // render that a time limit or a noise target ends; with a range, it is the whole render's.
    int spp = 0;
    double noise_target = 0.0; // stop at this estimated relative error (0: none)
    double checkpoint = -1.0;  // seconds of rendering between saved states (< 0: none)
    bool resume = false;       // rank 0 continues a state (RenderSession::resume)
    bool partial = false;      // a farm task: sample indices first .. end-1 only
    int first = 0, end = 0;    // the range of a partial render
    std::string state_path;    // where states are saved and read
    // A progressive render (extend): its end so far is no plan for a learning technique, which
    // would otherwise stop learning where a later call needs it.
    bool open_ended = false;
};

// A render that only a time limit or a noise target ends: neither capped by a user's spp nor a
// fixed range (the settings' spp is no cap then).
bool uncapped_render(const SessionOptions& o, const RenderSettings& st);

// Reports from a running session, on rank 0; each may be empty.
struct SessionCallbacks {
    std::function<void(int spp, double seconds)> progress; // after each round kept
    std::function<void(int spp)> progress_total;           // the next noise check's spp
    std::function<void(const std::string&)> note;          // a status line (stderr's)
};

struct SessionResult {
    FilmSums sums;     // every rank's film, summed on rank 0 (empty on the others)
    RenderStats stats; // ray and sample counts summed over the ranks (on rank 0)
    int spp = 0, first = 0, resumed_from = 0;
    int signal = 0;       // the stop request's signal (0: none)
    bool stopped = false; // a round was abandoned (a stop request or the time limit)
    double render_seconds = 0.0;
    // Of the film written (rank 0, whole renders); infinite where not measured.
    double noise_error = 0.0;
    bool noise_reached = false;
};

class RenderSession {
  public:
    // Makes the renderer of `prepared` (its settings: back end, device, threads). `cluster` and
    // `prepared` must outlive the session.
    RenderSession(const Cluster& cluster, const PreparedRender& prepared, SessionOptions options,
                  ProgramBuildInfo* build = nullptr);
    RenderSession(const RenderSession&) = delete;
    RenderSession& operator=(const RenderSession&) = delete;

    // Rank 0, before start(): continue from `state` (checked with check_resume_state).
    void resume(RenderState state) { resumed_ = std::move(state); }
    // Every rank: agree on the render (scene key and samples, else ClusterError naming the
    // difference) and take rank 0's resumed samples as the count done.
    void start();
    // Every rank: renders rounds until a stop rule holds; the film and counts summed to rank 0.
    SessionResult run(const SessionCallbacks& callbacks = {});
    // Asks a running session to stop as a signal `sig` would (safe from another thread).
    void request_stop(int sig) { stop_request_ = sig; }
    // A progressive front end's next call (rank of one, a whole render): moves the range's end to
    // sample `end` and clears a stop request, so that run() adds samples done() .. end-1 to the
    // same film, the bits of one run to `end`. Throws et::Error where the renderer cannot go on
    // (a stop abandoned a pass: continue from state_of(sums) in a new session).
    void extend(int64_t end);
    // Whether a stop abandoned a pass, so that this session renders no more.
    bool abandoned() const { return stopped_; }

    const Renderer& renderer() const { return *renderer_; }
    const PreparedRender& prepared() const { return prepared_; }
    const SessionOptions& options() const { return options_; }
    const RenderSettings& settings() const { return prepared_.scene.settings; }
    uint64_t key() const { return key_; }
    int64_t first() const { return first_; }
    int64_t end() const { return end_; }
    int64_t done() const { return done_; }
    int64_t resumed_from() const { return resumed_from_; }
    // The whole render's samples, kept in the state for merge (render_state.h).
    int whole_render() const;
    // The state of the film now: rank 0's, of `sums` (reduced over the ranks).
    RenderState state_of(FilmSums sums) const;

  private:
    struct RoundVerdict {
        bool stop = false, checkpoint = false;
    };
    int stop_signal() const;
    bool time_up() const;
    LearningPlan learning_plan() const;
    void agree_on_key() const;
    void agree_on_samples() const;
    void check_noise(const SessionCallbacks& cb);
    RoundVerdict agree_round();
    void save_checkpoint();
    void render_round(const SessionCallbacks& cb);
    SessionResult finish();

    const Cluster& cluster_;
    const PreparedRender& prepared_;
    SessionOptions options_;
    std::unique_ptr<Renderer> renderer_;
    uint64_t key_ = 0;
    RenderState resumed_;
    int64_t first_ = 0, end_ = 0, done_ = 0, resumed_from_ = 0;
    Timer render_, since_checkpoint_;
    std::string render_error_;
    int signal_ = 0;
    bool stopped_ = false;
    double noise_error_ = 0.0;
    bool noise_reached_ = false;
    int64_t next_check_ = 0;
    std::atomic<int> stop_request_{0};
};

} // namespace et
