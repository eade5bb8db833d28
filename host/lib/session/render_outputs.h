// The files a render writes, all-or-nothing (util/output_batch.h): the linear image with its
// metadata and AOV layers, the tone-mapped preview, the stats JSON and the resumable state.
#pragma once
#include "image/image_io.h"
#include "session/render_report.h"
#include "session/render_session.h"
#include "util/output_batch.h"

#include <memory>
#include <string>

namespace et {

struct RenderOutputs {
    std::string image;   // .exr / .hdr / .pfm; not written by a partial render
    std::string preview; // .png / .jpg ("": none); of the denoised image when there is one
    // The image denoised (image/denoise.h), guided by the film's AOVs when it has them ("": not
    // denoised). Beside the image, never in its place: the image stays the unbiased mean that
    // merge, resume and compare work on.
    std::string denoised;
    bool aov_layers = false; // the AOVs as EXR layers (the film may hold them for the denoiser)
    std::string stats;       // the report as JSON ("": none)
    std::string state;       // the resumable state
    // The state is written at the end of every render (--checkpoint, --resume, a sample range);
    // else only when a stop request (a signal) interrupted it, so that --resume continues it.
    bool keep_state = false;
    bool partial = false;     // a farm task: the state is its film, no image
    double exposure_ev = 0.0; // the preview's: radiance x 2^EV before the tone curve
    // LivePreview: rewrite the preview every this many seconds of rendering (< 0: never), and
    // with live_image the linear image too.
    double live_interval = -1.0;
    bool live_image = false;
};

// What write_outputs did beyond writing: the denoiser's time (0 and "" when not denoised).
struct OutputsWritten {
    double denoise_seconds = 0.0;
    std::string denoiser; // "Open Image Denoise 2.5.1 (FILE)"
};

// Reserves every output of a render once its inputs are read (none may be an input, but for the
// state a resumed render continues, and none may be two). Throws et::Error naming the path.
std::unique_ptr<OutputBatch> reserve_outputs(const RenderOutputs& o, bool resume);

// Whether a render with `result` leaves its state behind.
bool writes_state(const RenderOutputs& o, const SessionResult& result);

// The film's mean (`mean`, sums.mean()) denoised (image/denoise.h), guided by the film's albedo
// and normal where it holds AOVs; throws et::Error as denoise() does.
RgbImage denoise_film(const FilmSums& sums, const RgbImage& mean);

// Throws et::Error before a render whose outputs could not be written as planned: here, a
// denoised image without a denoiser (the message says how to install one).
void check_outputs_possible(const RenderOutputs& o);

// Rank 0: writes the outputs of `session`'s result into `batch` and commits them; then, for an
// interrupted render that keeps no state otherwise, its state (atomically, on its own). The
// film is final here: an interrupted render's partial film is denoised too.
OutputsWritten write_outputs(OutputBatch& batch, const RenderOutputs& o,
                             const RenderSession& session, const SessionResult& result,
                             const RenderReport& report);

// The film so far, written while it renders so that an image viewer shows it converge: the
// preview (and with RenderOutputs::live_image the linear image, without AOV layers) every
// live_interval seconds of rendering, and after the first round. Each write replaces its file
// atomically (a temporary renamed into place, util/output_batch.h): a viewer never reads half a
// file. Under MPI it shows rank 0's own samples; the final outputs hold every rank's.
class LivePreview {
  public:
    LivePreview(const RenderOutputs& o, const RenderSession& session);
    // From the session's progress callback (rank 0, between rounds): writes when due. A write
    // that fails is warned about, and ends the live previews, not the render.
    void update(int spp, double seconds);
    int writes() const { return writes_; }

  private:
    const RenderOutputs& outputs_;
    const RenderSession& session_;
    double last_ = 0.0;
    int writes_ = 0;
    bool failed_ = false; // a write failed: warned once, no more tried
};

} // namespace et
