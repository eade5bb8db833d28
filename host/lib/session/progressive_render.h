// A render that goes on where its last call stopped (the Python module's Renderer): one film of
// a prepared scene, extended call by call, so that calls adding up to N samples per pixel give
// the bits of one render of N (the sample indices run on: render_session.h). A stop request
// keeps the film; where it abandoned a pass, the next call continues the film in a new session
// resumed from it (as `render --resume` does), which a learning technique re-learns.
#pragma once
#include "load/scene.h"
#include "session/render_report.h"
#include "session/render_session.h"

#include <memory>
#include <string>

namespace et {

class ProgressiveRender {
  public:
    // Prepares `scene` for `settings` (prepare_render) and makes its session on a cluster of
    // one; `name` names the scene in messages and the report. `cluster` must outlive this.
    ProgressiveRender(const Cluster& cluster, Scene scene, const RenderSettings& settings,
                      std::string name);
    ProgressiveRender(const ProgressiveRender&) = delete;
    ProgressiveRender& operator=(const ProgressiveRender&) = delete;

    // Renders until the film holds `spp` samples per pixel (none if it holds them already), a
    // stop request or the settings' time limit; `callbacks` report as for RenderSession::run.
    const SessionResult& render_to(int spp, const SessionCallbacks& callbacks = {});
    // Asks the render in progress to stop (safe from another thread): it keeps the film.
    void request_stop(int sig) { session_->request_stop(sig); }

    // The film and counts after the last call (empty before the first).
    const SessionResult& result() const { return result_; }
    int spp() const { return result_.spp; }
    const PreparedRender& prepared() const { return *prepared_; }
    // The facts of the last call's render, as `render --stats` writes them.
    RenderReport report() const;

  private:
    void new_session(RenderState resumed);

    const Cluster& cluster_;
    std::string name_;
    std::unique_ptr<PreparedRender> prepared_;
    ProgramBuildInfo build_;
    std::unique_ptr<RenderSession> session_;
    SessionResult result_;
};

} // namespace et
