// envtrace merge: the partial films of farm tasks (`render --sample-range A:B`) summed into one
// image. The sums are exact (render/film_sums.h), so the parts of a full cover of 0 .. N-1 give
// the image of one render to N spp bit for bit, in whatever order they are named. Parts of
// another render (scene, inputs, settings, back end, envtrace: the render key) or of another
// film size are refused, as are overlapping ranges (samples counted twice) and, unless
// --allow-gaps, missing samples.
#include "commands.h"
#include "image/denoise.h"
#include "image/image_io.h"
#include "image/preview.h"
#include "render/film_layers.h"
#include "render/noise_estimate.h"
#include "render/render_state.h"
#include "session/render_outputs.h"
#include "util/error.h"
#include "util/output_batch.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace et::cli {
namespace {

struct MergeArgs {
    std::vector<std::string> parts;
    std::string output, state;
    bool allow_gaps = false;
    bool denoise = false;
};

struct Part {
    std::string path;
    RenderState state;
    int64_t first() const { return state.first; }
    int64_t end() const { return int64_t(state.first) + state.spp; }
};

std::string samples_text(int64_t first, int64_t end) {
    return end - first == 1 ? "sample " + std::to_string(first)
                            : "samples " + std::to_string(first) + ".." + std::to_string(end - 1);
}

void run(const MergeArgs& a) {
    auto [exr_name, png_name] = output_names(a.output);
    check_writable_format(exr_name);
    if (!png_name.empty())
        check_writable_format(png_name);
    const std::string denoised = a.denoise ? denoised_name(exr_name) : "";
    if (a.denoise) {
        check_writable_format(denoised);
        check_denoiser();
    }
    std::vector<Part> parts;
    for (const std::string& path : a.parts) {
        parts.push_back({path, read_render_state(path)});
        const Part& p = parts.back();
        const Part& ref = parts.front();
        if (p.state.sums.width() != ref.state.sums.width() ||
            p.state.sums.height() != ref.state.sums.height())
            throw Error(path + ": a " + std::to_string(p.state.sums.width()) + "x" +
                        std::to_string(p.state.sums.height()) + " film, but " + ref.path + " is " +
                        std::to_string(ref.state.sums.width()) + "x" +
                        std::to_string(ref.state.sums.height()) + ": not parts of one render");
        if (p.state.key != ref.state.key)
            throw Error(path + ": a part of another render than " + ref.path +
                        " (the scene, its inputs, the settings, the back end or envtrace differ): "
                        "their samples do not belong to one image");
        if (p.state.spp == 0)
            throw Error(path + ": the part holds no samples");
    }
    std::vector<const Part*> order;
    for (const Part& p : parts)
        order.push_back(&p);
    std::sort(order.begin(), order.end(),
              [](const Part* x, const Part* y) { return x->first() < y->first(); });
    std::vector<std::string> gaps;
    int64_t covered = 0;
    // The whole render's samples as the parts' tasks were asked for (render_state.h): a part
    // missing at the end, or a last task stopped early, is a gap too (it merged unnoticed).
    int64_t total = 0;
    const Part* asked = nullptr;
    for (const Part& p : parts)
        if (p.state.total > total) {
            total = p.state.total;
            asked = &p;
        }
    for (size_t i = 0; i < order.size(); ++i) {
        const Part& p = *order[i];
        if (i > 0 && p.first() < order[i - 1]->end())
            throw Error(p.path + " (" + samples_text(p.first(), p.end()) + ") and " +
                        order[i - 1]->path + " (" +
                        samples_text(order[i - 1]->first(), order[i - 1]->end()) +
                        ") overlap: their common samples would count twice");
        if (p.first() > covered)
            gaps.push_back(samples_text(covered, p.first()));
        covered = p.end();
    }
    if (total > covered)
        gaps.push_back(samples_text(covered, total) + " (" + asked->path + " is a part of " +
                       std::to_string(total) + " samples)");
    const int64_t last = std::max(covered, total);
    if (!gaps.empty()) {
        std::string list;
        for (const std::string& g : gaps)
            list += (list.empty() ? "" : ", ") + g;
        if (!a.allow_gaps)
            throw Error("the parts do not cover samples 0.." + std::to_string(last - 1) +
                        ": missing " + list +
                        " (render them with --sample-range, or merge anyway with --allow-gaps)");
        if (!a.state.empty())
            throw Error("--state: the parts leave gaps (" + list +
                        "): a merged state must hold consecutive samples from 0");
        warn("the parts leave gaps: missing " + list +
             "; the image is a valid estimate, but not "
             "the render of samples 0.." +
             std::to_string(last - 1));
    }

    const RenderState& ref = parts.front().state;
    RenderState merged{ref.key, 0, 0,
                       FilmSums(ref.sums.width(), ref.sums.height(), ref.sums.has_aovs()),
                       static_cast<int>(total > 0 ? last : 0)}; // (a version 3 part: total 0)
    std::string ranges;
    for (const Part* p : order) {
        merged.sums.add(p->state.sums);
        merged.spp += p->state.spp;
        ranges += (ranges.empty() ? "" : ",") + std::to_string(p->first()) + ":" +
                  std::to_string(p->end());
    }
    std::vector<std::string> targets = {exr_name};
    if (!png_name.empty())
        targets.push_back(png_name);
    if (!a.state.empty())
        targets.push_back(a.state);
    if (a.denoise)
        targets.push_back(denoised);
    OutputBatch outputs(targets);
    const int w = merged.sums.width(), h = merged.sums.height();
    const std::vector<float> img = merged.sums.mean();
    std::vector<std::pair<std::string, std::string>> meta = {
        {"envtrace:spp", std::to_string(merged.spp)},
        {"envtrace:interrupted", "no"},
        {"envtrace:sample_ranges", ranges},
        {"envtrace:merged_parts", std::to_string(parts.size())},
        {"Software", "envtrace " ENVTRACE_VERSION},
    };
    if (merged.sums.has_aovs()) { // the layers of `render --aovs` (render/film_layers.h)
        char error_text[32];
        std::snprintf(error_text, sizeof error_text, "%.6g", relative_error(merged.sums));
        meta.emplace_back("envtrace:noise_error", error_text);
        const FilmLayers layers = film_layers(merged.sums);
        write_image_channels(outputs, exr_name, w, h, layers.names, layers.pixels, meta);
    } else {
        write_image(outputs, exr_name, w, h, 3, img, meta);
    }
    RgbImage film{w, h, img};
    if (a.denoise) { // as render --denoise does (session/render_outputs.h)
        film = denoise_film(merged.sums, film);
        meta.emplace_back("envtrace:denoiser", check_denoiser());
        write_image(outputs, denoised, w, h, 3, film.rgb, meta);
    }
    if (!png_name.empty())
        write_image(outputs, png_name, w, h, 3, tone_map(film, 1.0f));
    if (!a.state.empty())
        write_render_state(outputs, a.state, merged);
    outputs.commit();
    std::printf("merged %zu part%s (%s%s) into %s%s%s%s%s%s%s: %d spp\n", parts.size(),
                parts.size() == 1 ? "" : "s", samples_text(0, covered).c_str(),
                gaps.empty() ? "" : ", with gaps", exr_name.c_str(), a.denoise ? " and " : "",
                denoised.c_str(), png_name.empty() ? "" : " and ", png_name.c_str(),
                a.state.empty() ? "" : " and ", a.state.c_str(), merged.spp);
}

} // namespace

void add_merge_command(CLI::App& app, Globals&) {
    auto a = std::make_shared<MergeArgs>();
    auto* cmd = app.add_subcommand(
        "merge", "Sum the partial films of 'render --sample-range' tasks into one image");
    cmd->add_option("parts", a->parts, "Partial films (.envtrace-state) of one render")->required();
    cmd->add_option("-o,--output", a->output,
                    "Output image: .exr/.hdr/.pfm (linear) plus a .png preview beside it")
        ->required();
    cmd->add_option("--state", a->state,
                    "Also write the merged film as a render state (to resume or merge further)");
    cmd->add_flag("--allow-gaps", a->allow_gaps,
                  "Write the image even if some sample indices are in no part");
    cmd->add_flag("--denoise", a->denoise,
                  "Also write OUT.denoised.EXT as 'render --denoise' does (guided by the AOVs of "
                  "parts rendered with --aovs; the preview shows it)");
    cmd->callback([a] { run(*a); });
}

} // namespace et::cli
