#include "render_print.h"

#include "render/learning_summary.h"
#include "util/error.h"
#include "util/interrupt.h"

#include <algorithm>
#include <cstdio>

namespace et::cli {

void print_prepared(const std::string& scene, const PreparedRender& p) {
    const DeviceScene& ds = p.scene;
    if (ds.settings.strategy == Strategy::lights)
        std::printf("light set %s: %zu directional lights (%s)\n", ds.settings.lights.c_str(),
                    p.light_set.lights.size(), p.light_set.method.c_str());
    if (ds.settings.strategy == Strategy::sis) {
        std::printf("SIS: %d strata (per level:", ds.settings.sis_samples);
        for (int n : p.sis.level_samples)
            std::printf(" %d", n);
        std::printf(") precomputed in %.3f s\n", p.sis.seconds);
    }
    std::printf("scene %s: %zu triangles, BVH %d nodes (depth %d, SAH cost %.1f) in %.1f ms; "
                "environment %dx%d, distribution in %.2f ms\n",
                scene.c_str(), ds.triangle_count, ds.bvh.nodes, ds.bvh.depth, ds.bvh.sah_cost,
                ds.bvh.build_seconds * 1e3, ds.map_width, ds.map_height,
                ds.map_build_seconds * 1e3);
}

void print_start(const RenderSession& s, const ProgramBuildInfo& build, const Cluster& cl) {
    const RenderSettings& st = s.settings();
    const DeviceScene& ds = s.prepared().scene;
    if (st.backend == Backend::opencl)
        std::printf("OpenCL program build %.3f s (%s)\n", build.seconds,
                    build.from_cache ? "cached binary" : "compiled");
    if (s.options().resume && cl.root())
        std::printf("resumed from %s at %d spp\n", s.options().state_path.c_str(),
                    static_cast<int>(s.resumed_from()));
    const std::string spp =
        st.time_limit > 0 ? "time-limited" : std::to_string(s.end() - s.first());
    const std::string range = s.options().partial ? " (samples " + std::to_string(s.first()) +
                                                        ".." + std::to_string(s.end() - 1) + ")"
                                                  : "";
    const std::string ranks = cl.size() > 1 ? ", " + std::to_string(cl.size()) + " MPI ranks" : "";
    std::printf("backend %s: %dx%d, %s spp%s, depth %d, strategy %s, sampler %s, %d paths in "
                "flight%s\n",
                s.renderer().name().c_str(), ds.width(), ds.height(), spp.c_str(), range.c_str(),
                st.max_depth, name_of(st.strategy), name_of(st.sampler), s.renderer().paths(),
                ranks.c_str());
    std::fflush(stdout);
}

void print_stop(const RenderSession& s, const RenderOutputs& o, const SessionResult& r,
                const Cluster& cl) {
    if (!cl.root())
        return;
    if (r.stopped && !r.signal)
        std::fprintf(stderr,
                     "envtrace: time limit of %g s reached inside a pass: that pass is dropped, "
                     "the image holds the %d spp before it\n",
                     s.settings().time_limit, r.spp);
    if (r.signal)
        std::fprintf(stderr,
                     "envtrace: %s: stopped at %d spp; writing %s%s (--resume continues it; "
                     "a second signal stops at once)\n",
                     signal_name(r.signal), r.spp,
                     o.partial ? "the partial film " : "the image and the state ", o.state.c_str());
}

void print_summary(const RenderSession& s, const RenderOutputs& o, const SessionResult& r,
                   const OutputsWritten& w, double total, const Cluster& cl) {
    const RenderStats& st = r.stats;
    const DeviceScene& ds = s.prepared().scene;
    const double target = s.options().noise_target;
    const int rendered = r.spp - r.resumed_from;
    const double secs = r.render_seconds;
    std::printf("rendered %d spp in %.2f s: %.2f Mrays/s (%llu camera, %llu continuation, %llu "
                "shadow), %.3g samples/s, %.4f s/spp%s\n",
                rendered, secs, st.rays() / secs * 1e-6, (unsigned long long)st.camera_rays,
                (unsigned long long)st.continuation_rays, (unsigned long long)st.shadow_rays,
                double(rendered) * ds.width() * ds.height() / secs, secs / std::max(1, rendered),
                r.stopped ? " (the time and rays include the pass abandoned at the stop)" : "");
    const std::string learning = learning_summary(st.learning);
    if (!learning.empty())
        std::printf("%s\n", learning.c_str());
    if (st.nonfinite_samples > 0 && cl.root())
        warn(s.options().scene + ": " + std::to_string(st.nonfinite_samples) +
             " samples were not finite and counted as zero (a renderer bug: please "
             "report the scene)");
    std::printf("%s time per stage, summed over the lanes%s:",
                ds.settings.backend == Backend::cpu ? "thread" : "device",
                cl.size() > 1 ? " (rank 0)" : "");
    for (const auto& [name, t] : st.stage_seconds)
        std::printf(" %s %.3fs", name.c_str(), t);
    const bool state = writes_state(o, r);
    if (o.partial)
        std::printf("\nwrote the partial film %s (samples %d..%d)%s%s (total %.2f s)\n",
                    o.state.c_str(), r.first, r.first + r.spp - 1, o.stats.empty() ? "" : " and ",
                    o.stats.c_str(), total);
    else
        std::printf("\nwrote %s%s%s%s%s%s%s at %d spp (total %.2f s)\n", o.image.c_str(),
                    o.denoised.empty() ? "" : " and ", o.denoised.c_str(),
                    o.preview.empty() ? "" : " and ", o.preview.c_str(),
                    state ? " and the state " : "", state ? o.state.c_str() : "", r.spp, total);
    if (!w.denoiser.empty())
        std::printf("denoised in %.3f s by %s\n", w.denoise_seconds, w.denoiser.c_str());
    if (target > 0 && cl.root())
        std::printf("noise target %g %s at %d spp: estimated relative error %.4g\n", target,
                    r.noise_reached ? "reached" : "NOT reached", r.spp, r.noise_error);
}

} // namespace et::cli
