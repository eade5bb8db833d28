// What `envtrace render` says: the prepared scene, the render about to start, why it stopped
// early (stderr) and the summary of what it rendered and wrote (stdout, rank 0's).
#pragma once
#include "session/cluster.h"
#include "session/render_outputs.h"
#include "session/render_session.h"

#include <string>

namespace et::cli {

void print_prepared(const std::string& scene, const PreparedRender& p);
// Back end, film, samples and ranks of the render about to start.
void print_start(const RenderSession& s, const ProgramBuildInfo& build, const Cluster& cl);
// Why the render stopped early, on stderr, and where its state is for --resume.
void print_stop(const RenderSession& s, const RenderOutputs& o, const SessionResult& r,
                const Cluster& cl);
// The summary on stdout: rates, stage times, what was written (and denoised).
void print_summary(const RenderSession& s, const RenderOutputs& o, const SessionResult& r,
                   const OutputsWritten& w, double total, const Cluster& cl);

} // namespace et::cli
