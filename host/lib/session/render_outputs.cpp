#include "session/render_outputs.h"

#include "image/image_io.h"
#include "image/preview.h"
#include "render/film_layers.h"
#include "util/json_file.h"

#include <cmath>

namespace et {

std::unique_ptr<OutputBatch> reserve_outputs(const RenderOutputs& o, bool resume) {
    std::vector<std::string> targets;
    if (!o.partial)
        targets.push_back(o.image);
    if (!o.partial && !o.preview.empty())
        targets.push_back(o.preview);
    if (!o.stats.empty())
        targets.push_back(o.stats);
    if (o.keep_state)
        targets.push_back(o.state);
    return std::make_unique<OutputBatch>(targets, resume ? std::vector<std::string>{o.state}
                                                         : std::vector<std::string>{});
}

bool writes_state(const RenderOutputs& o, const SessionResult& result) {
    return o.keep_state || result.signal != 0;
}

namespace {

// The image with its metadata (and AOV layers), and its preview.
void write_images(OutputBatch& batch, const RenderOutputs& o, const SessionResult& result,
                  const RenderReport& report) {
    const FilmSums& sums = result.sums;
    const int w = sums.width(), h = sums.height();
    const auto meta = report_metadata(report);
    const std::vector<float> img = sums.mean();
    if (sums.has_aovs()) {
        const FilmLayers layers = film_layers(sums);
        write_image_channels(batch, o.image, w, h, layers.names, layers.pixels, meta);
    } else {
        write_image(batch, o.image, w, h, 3, img, meta);
    }
    if (o.preview.empty())
        return;
    const RgbImage film{w, h, img};
    const float exposure = static_cast<float>(std::exp2(o.exposure_ev));
    write_image(batch, o.preview, w, h, 3, tone_map(film, exposure));
}

} // namespace

void write_outputs(OutputBatch& batch, const RenderOutputs& o, const RenderSession& session,
                   const SessionResult& result, const RenderReport& report) {
    if (!o.partial)
        write_images(batch, o, result, report);
    if (!o.stats.empty())
        write_json_file(batch, o.stats, report_json(report), 2);
    if (o.keep_state)
        write_render_state(batch, o.state, session.state_of(result.sums));
    batch.commit();
    if (!o.keep_state && writes_state(o, result))
        write_render_state(o.state, session.state_of(result.sums));
}

} // namespace et
