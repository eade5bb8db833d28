// `envtrace render`: options -> settings -> a RenderSession (host/lib/session) -> what it wrote.
// Under mpirun every rank runs this; rank 0 speaks for the render and writes its outputs.
#include "commands.h"
#include "progress.h"
#include "render_options.h"

#include "image/image_io.h"
#include "load/scene.h"
#include "session/checkpoint.h"
#include "session/cluster.h"
#include "session/render_outputs.h"
#include "session/render_session.h"
#include "util/error.h"
#include "util/file_check.h"
#include "util/interrupt.h"
#include "util/timer.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <tuple>

namespace fs = std::filesystem;

namespace et::cli {

// out.exr -> (out.exr, out.png); out.png -> (out.exr, out.png). A build without OpenImageIO
// writes no preview: out.pfm -> (out.pfm, "").
std::pair<std::string, std::string> output_names(const std::string& out) {
    fs::path p(out);
    std::error_code ec;
    if (!out.empty() && (out.back() == '/' || p.filename() == "." || p.filename() == ".." ||
                         fs::is_directory(p, ec)))
        throw Error(out + ": is a folder: name the image to write in it (e.g. " +
                    (fs::path(out) / "render.exr").lexically_normal().string() + ")");
    const std::string ext = lower_extension(out);
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg")
        return {fs::path(p).replace_extension(".exr").string(), out};
    if (ext == ".exr" || ext == ".hdr" || ext == ".pfm")
        return {out, have_image_library() ? fs::path(p).replace_extension(".png").string() : ""};
    throw Error(out + ": unsupported output format '" + ext +
                "' (use .exr, .hdr, .pfm, or .png / .jpg for the preview beside an .exr)");
}

namespace {

// What one rank has set up before rendering: everything read, prepared and (rank 0) reserved.
struct Setup {
    SessionOptions options;
    RenderOutputs outputs;
    std::unique_ptr<PreparedRender> prepared;
    std::unique_ptr<OutputBatch> batch; // rank 0
    ProgramBuildInfo build;
    std::unique_ptr<RenderSession> session;
};

SessionOptions session_options(const RenderArgs& a) {
    SessionOptions o;
    o.scene = a.scene;
    o.spp = a.spp;
    o.noise_target = a.noise_target;
    o.checkpoint = a.checkpoint;
    o.resume = a.resume;
    o.partial = !a.sample_range.empty();
    if (!o.partial)
        return o;
    std::tie(o.first, o.end) = parse_sample_range(a.sample_range);
    if (a.time_limit >= 0 || a.noise_target > 0)
        throw Error("--sample-range renders a fixed range of sample indices: it excludes "
                    "--time-limit and --noise-target");
    // --spp with a range: the whole render's samples, which merge checks are all there.
    if (a.spp > 0 && o.end > a.spp)
        throw Error("--sample-range " + a.sample_range + " reaches past --spp " +
                    std::to_string(a.spp) + " (with a range, --spp is the whole render's samples)");
    return o;
}

// -o, else renders/ + the scene's output (else SCENE.exr) under the current folder: a first
// render from a checkout lands in a folder .gitignore lists, not among the sources. Rank 0
// creates the folder.
std::string output_name(const RenderArgs& a, const Scene& scene, bool root) {
    if (!a.output.empty())
        return a.output;
    const fs::path name =
        !scene.output.empty() ? fs::path(scene.output) : fs::path(a.scene).stem().concat(".exr");
    const fs::path out = fs::path(kDefaultOutputFolder) / name; // an absolute name stays
    if (root && out.has_parent_path())
        fs::create_directories(out.parent_path());
    return out.string();
}

// The outputs' names, checked before any time is spent rendering.
RenderOutputs plan_outputs(const RenderArgs& a, const Scene& scene, const RenderSettings& st,
                           const SessionOptions& so, bool root) {
    RenderOutputs o;
    std::tie(o.image, o.preview) = output_names(output_name(a, scene, root));
    if (st.aovs && !so.partial && fs::path(o.image).extension() != ".exr")
        throw Error(o.image + ": --aovs writes its layers into an OpenEXR image: name an "
                              ".exr output (-o)");
    check_writable_format(o.image);
    if (!o.preview.empty())
        check_writable_format(o.preview);
    o.keep_state = a.checkpoint >= 0 || a.resume || so.partial;
    if (!a.state.empty() && !o.keep_state)
        throw Error("--state " + a.state +
                    ": names the state of --checkpoint, --resume or --sample-range; this render "
                    "keeps none (add --checkpoint SECONDS to save one)");
    o.state = !a.state.empty() ? a.state
              : so.partial     ? partial_state_path(o.image, so.first, so.end)
                               : default_state_path(o.image);
    o.stats = a.stats_file;
    o.partial = so.partial;
    o.exposure_ev = a.exposure;
    return o;
}

void print_prepared(const RenderArgs& a, const PreparedRender& p) {
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
                a.scene.c_str(), ds.triangle_count, ds.bvh.nodes, ds.bvh.depth, ds.bvh.sah_cost,
                ds.bvh.build_seconds * 1e3, ds.map_width, ds.map_height,
                ds.map_build_seconds * 1e3);
}

// Every rank reads and prepares everything; rank 0 alone reads the state and reserves the
// outputs, once every input has been read.
void set_up(const RenderArgs& a, const Globals& g, Setup& s) {
    const Cluster& cl = *g.cluster;
    s.options = session_options(a);
    Scene scene = load_scene(a.scene);
    scene.width = a.width > 0 ? a.width : scene.width;
    scene.height = a.height > 0 ? a.height : scene.height;
    const RenderSettings st = settings_for(a, g, scene.settings);
    // A farm task of SIS: whole rounds of its strata, so that the merged tasks are too.
    if (s.options.partial && st.strategy == Strategy::sis &&
        (s.options.first % st.sis_samples != 0 || s.options.end % st.sis_samples != 0))
        throw Error("--strategy sis visits one stratum per sample: --sample-range (" +
                    a.sample_range + ") must start and end at multiples of --sis-samples (" +
                    std::to_string(st.sis_samples) + ")");
    s.outputs = plan_outputs(a, scene, st, s.options, cl.root());
    s.options.state_path = s.outputs.state;
    s.prepared = prepare_render(std::move(scene), st);
    print_prepared(a, *s.prepared);
    RenderState state;
    if (a.resume && cl.root()) {
        state = read_render_state(s.outputs.state);
        check_resume_state(state, s.prepared->scene, s.options,
                           s.options.partial ? "--sample-range"
                           : a.spp > 0       ? "--spp"
                                             : "the scene's render.spp");
    }
    if (cl.root())
        s.batch = reserve_outputs(s.outputs, a.resume);
    s.session = std::make_unique<RenderSession>(cl, *s.prepared, s.options, &s.build);
    s.session->resume(std::move(state));
}

void print_start(const Setup& setup, const Cluster& cl) {
    const RenderSession& s = *setup.session;
    const RenderSettings& st = s.settings();
    const DeviceScene& ds = s.prepared().scene;
    if (st.backend == Backend::opencl)
        std::printf("OpenCL program build %.3f s (%s)\n", setup.build.seconds,
                    setup.build.from_cache ? "cached binary" : "compiled");
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

// Renders on every rank; a first SIGINT/SIGTERM (InterruptHandler) stops the session, which
// keeps the rounds before it, and the outputs are then written under the same handler: a
// second signal ends the process at once, writing nothing more.
SessionResult render(RenderSession& session, const Cluster& cl) {
    Progress progress(static_cast<int>(session.end() - session.first()),
                      session.settings().time_limit);
    SessionCallbacks cb;
    cb.progress = [&](int done, double seconds) { progress.update(done, seconds); };
    cb.progress_total = [&](int total) { progress.set_total(total); };
    cb.note = [](const std::string& line) { std::fprintf(stderr, "envtrace: %s\n", line.c_str()); };
    SessionResult r = session.run(cl.root() ? cb : SessionCallbacks{});
    progress.finish();
    return r;
}

// Why the render stopped early, on stderr, and where its state is for --resume.
void print_stop(const Setup& s, const SessionResult& r, const Cluster& cl) {
    if (!cl.root())
        return;
    if (r.stopped && !r.signal)
        std::fprintf(stderr,
                     "envtrace: time limit of %g s reached inside a pass: that pass is dropped, "
                     "the image holds the %d spp before it\n",
                     s.session->settings().time_limit, r.spp);
    if (r.signal)
        std::fprintf(stderr,
                     "envtrace: %s: stopped at %d spp; writing the %s and the state %s "
                     "(--resume continues it; a second signal stops at once)\n",
                     signal_name(r.signal), r.spp, s.outputs.partial ? "partial film" : "image",
                     s.outputs.state.c_str());
}

// The summary on stdout: rates, stage times, what was written.
void print_summary(const RenderArgs& a, const Setup& s, const SessionResult& r, double total,
                   const Cluster& cl) {
    const RenderStats& st = r.stats;
    const DeviceScene& ds = s.prepared->scene;
    const int rendered = r.spp - r.resumed_from;
    const double secs = r.render_seconds;
    std::printf("rendered %d spp in %.2f s: %.2f Mrays/s (%llu camera, %llu continuation, %llu "
                "shadow), %.3g samples/s, %.4f s/spp%s\n",
                rendered, secs, st.rays() / secs * 1e-6, (unsigned long long)st.camera_rays,
                (unsigned long long)st.continuation_rays, (unsigned long long)st.shadow_rays,
                double(rendered) * ds.width() * ds.height() / secs, secs / std::max(1, rendered),
                r.stopped ? " (the time and rays include the pass abandoned at the stop)" : "");
    if (st.nonfinite_samples > 0 && cl.root())
        warn(a.scene + ": " + std::to_string(st.nonfinite_samples) +
             " samples were not finite and counted as zero (a renderer bug: please "
             "report the scene)");
    std::printf("%s time per stage, summed over the lanes%s:",
                ds.settings.backend == Backend::cpu ? "thread" : "device",
                cl.size() > 1 ? " (rank 0)" : "");
    for (const auto& [name, t] : st.stage_seconds)
        std::printf(" %s %.3fs", name.c_str(), t);
    const RenderOutputs& o = s.outputs;
    const bool state = writes_state(o, r);
    if (o.partial)
        std::printf("\nwrote the partial film %s (samples %d..%d)%s%s (total %.2f s)\n",
                    o.state.c_str(), r.first, r.first + r.spp - 1, o.stats.empty() ? "" : " and ",
                    o.stats.c_str(), total);
    else
        std::printf("\nwrote %s%s%s%s%s at %d spp (total %.2f s)\n", o.image.c_str(),
                    o.preview.empty() ? "" : " and ", o.preview.c_str(),
                    state ? " and the state " : "", state ? o.state.c_str() : "", r.spp, total);
    if (a.noise_target > 0 && cl.root())
        std::printf("noise target %g %s at %d spp: estimated relative error %.4g\n", a.noise_target,
                    r.noise_reached ? "reached" : "NOT reached", r.spp, r.noise_error);
}

void run(const RenderArgs& a, Globals& g) {
    const Cluster& cl = *g.cluster;
    if (cl.launched_without_mpi())
        throw Error("started by mpirun as one of several ranks, but this envtrace was built "
                    "without MPI (configure with libopenmpi-dev installed, ENVTRACE_MPI=AUTO or "
                    "ON): each rank would render the whole image alone");
    // Rank 0 speaks for the render; the other ranks' errors reach it through Cluster::check.
    if (!cl.root() && !std::freopen("/dev/null", "w", stdout))
        throw Error("cannot redirect the standard output of " + cl.describe(cl.rank()));
    Timer total;
    Setup s;
    cl.check(attempt([&] { set_up(a, g, s); }));
    s.session->start();
    print_start(s, cl);
    InterruptHandler interrupts;
    const SessionResult r = render(*s.session, cl);
    print_stop(s, r, cl);
    cl.check(attempt([&] {
        if (cl.root())
            write_outputs(*s.batch, s.outputs, *s.session, r,
                          render_report({*s.session, r, s.build, cl.size()}));
    }));
    print_summary(a, s, r, total.seconds(), cl);
    if (r.signal)
        g.exit_code = 128 + r.signal;
}

} // namespace

void add_render_command(CLI::App& app, Globals& g) {
    auto a = std::make_shared<RenderArgs>();
    auto* cmd = app.add_subcommand("render", "Render a scene file with the wavefront path tracer");
    add_render_options(*cmd, *a);
    cmd->callback([a, &g, cmd, &app] {
        a->light_samples_given = cmd->count("--light-samples") > 0;
        a->bsdf_samples_given = cmd->count("--bsdf-samples") > 0;
        a->sis_samples_given = cmd->count("--sis-samples") > 0;
        a->paths_given = cmd->count("--paths") > 0;
        a->device_given = app.count("--device") > 0;
        run(*a, g);
    });
}

} // namespace et::cli
