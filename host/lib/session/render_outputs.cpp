#include "session/render_outputs.h"

#include "image/denoise.h"
#include "image/image_io.h"
#include "image/preview.h"
#include "render/film_layers.h"
#include "session/cluster.h"
#include "util/error.h"
#include "util/json_file.h"
#include "util/timer.h"

#include <cmath>

namespace et {

std::unique_ptr<OutputBatch> reserve_outputs(const RenderOutputs& o, bool resume) {
    std::vector<std::string> targets;
    if (!o.partial)
        targets.push_back(o.image);
    if (!o.partial && !o.preview.empty())
        targets.push_back(o.preview);
    if (!o.partial && !o.denoised.empty())
        targets.push_back(o.denoised);
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

RgbImage denoise_film(const FilmSums& sums, const RgbImage& mean) {
    if (!sums.has_aovs())
        return denoise(mean, {}, {});
    AovImages aov = sums.aov_images();
    const int w = sums.width(), h = sums.height();
    return denoise(mean, RgbImage{w, h, std::move(aov.albedo)},
                   RgbImage{w, h, std::move(aov.normal)});
}

void check_outputs_possible(const RenderOutputs& o) {
    if (!o.partial && !o.denoised.empty())
        check_denoiser();
}

namespace {

using Attributes = std::vector<std::pair<std::string, std::string>>;

// The image as the film's mean, or (aov_layers) with its AOV layers.
void write_linear(OutputBatch& batch, const RenderOutputs& o, const FilmSums& sums,
                  const std::vector<float>& mean, const Attributes& meta) {
    const int w = sums.width(), h = sums.height();
    if (o.aov_layers && sums.has_aovs()) {
        const FilmLayers layers = film_layers(sums);
        write_image_channels(batch, o.image, w, h, layers.names, layers.pixels, meta);
    } else {
        write_image(batch, o.image, w, h, 3, mean, meta);
    }
}

void write_preview(OutputBatch* batch, const RenderOutputs& o, const RgbImage& shown) {
    const float exposure = static_cast<float>(std::exp2(o.exposure_ev));
    const std::vector<float> display = tone_map(shown, exposure);
    if (batch)
        write_image(*batch, o.preview, shown.width, shown.height, 3, display);
    else
        write_image(o.preview, shown.width, shown.height, 3, display);
}

// The image with its metadata (and AOV layers), the denoised image, and the preview of the last.
OutputsWritten write_images(OutputBatch& batch, const RenderOutputs& o, const FilmSums& sums,
                            const Attributes& meta) {
    OutputsWritten done;
    const RgbImage film{sums.width(), sums.height(), sums.mean()};
    write_linear(batch, o, sums, film.rgb, meta);
    RgbImage denoised;
    if (!o.denoised.empty()) {
        const Timer t;
        denoised = denoise_film(sums, film);
        done.denoise_seconds = t.seconds();
        done.denoiser = check_denoiser();
        Attributes dmeta = meta;
        dmeta.emplace_back("envtrace:denoiser", done.denoiser);
        write_image(batch, o.denoised, denoised.width, denoised.height, 3, denoised.rgb, dmeta);
    }
    if (!o.preview.empty())
        write_preview(&batch, o, o.denoised.empty() ? film : denoised);
    return done;
}

} // namespace

OutputsWritten write_outputs(OutputBatch& batch, const RenderOutputs& o,
                             const RenderSession& session, const SessionResult& result,
                             const RenderReport& report) {
    OutputsWritten done;
    if (!o.partial)
        done = write_images(batch, o, result.sums, report_metadata(report));
    if (!o.stats.empty()) {
        nlohmann::json stats = report_json(report);
        if (!done.denoiser.empty())
            stats["denoise"] = {{"image", o.denoised},
                                {"denoiser", done.denoiser},
                                {"seconds", done.denoise_seconds}};
        write_json_file(batch, o.stats, stats, 2);
    }
    if (o.keep_state)
        write_render_state(batch, o.state, session.state_of(result.sums));
    batch.commit();
    if (!o.keep_state && writes_state(o, result))
        write_render_state(o.state, session.state_of(result.sums));
    return done;
}

LivePreview::LivePreview(const RenderOutputs& o, const RenderSession& session)
    : outputs_(o), session_(session) {}

void LivePreview::update(int spp, double seconds) {
    const RenderOutputs& o = outputs_;
    if (failed_ || o.live_interval < 0 || o.partial ||
        (writes_ > 0 && seconds - last_ < o.live_interval))
        return;
    last_ = seconds;
    ++writes_;
    const FilmSums& sums = session_.renderer().sums();
    const RgbImage film{sums.width(), sums.height(), sums.mean()};
    // A preview that cannot be written (a full disk) is no reason to lose the render.
    const std::string error = attempt([&] {
        if (!o.preview.empty())
            write_preview(nullptr, o, film);
        if (o.live_image)
            write_image(o.image, film.width, film.height, 3, film.rgb,
                        {{"envtrace:spp", std::to_string(spp)}, {"envtrace:live_preview", "1"}});
    });
    if (!error.empty()) {
        failed_ = true;
        warn(error + ": no more live previews; the render goes on");
    }
}

} // namespace et
