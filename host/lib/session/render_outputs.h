// The files a render writes, all-or-nothing (util/output_batch.h): the linear image with its
// metadata and AOV layers, the tone-mapped preview, the stats JSON and the resumable state.
#pragma once
#include "session/render_report.h"
#include "session/render_session.h"
#include "util/output_batch.h"

#include <memory>
#include <string>

namespace et {

struct RenderOutputs {
    std::string image;   // .exr / .hdr / .pfm; not written by a partial render
    std::string preview; // .png / .jpg ("": none)
    std::string stats;   // the report as JSON ("": none)
    std::string state;   // the resumable state
    // The state is written at the end of every render (--checkpoint, --resume, a sample range);
    // else only when a stop request (a signal) interrupted it, so that --resume continues it.
    bool keep_state = false;
    bool partial = false;     // a farm task: the state is its film, no image
    double exposure_ev = 0.0; // the preview's: radiance x 2^EV before the tone curve
};

// Reserves every output of a render once its inputs are read (none may be an input, but for the
// state a resumed render continues, and none may be two). Throws et::Error naming the path.
std::unique_ptr<OutputBatch> reserve_outputs(const RenderOutputs& o, bool resume);

// Whether a render with `result` leaves its state behind.
bool writes_state(const RenderOutputs& o, const SessionResult& result);

// Rank 0: writes the outputs of `session`'s result into `batch` and commits them; then, for an
// interrupted render that keeps no state otherwise, its state (atomically, on its own).
void write_outputs(OutputBatch& batch, const RenderOutputs& o, const RenderSession& session,
                   const SessionResult& result, const RenderReport& report);

} // namespace et
