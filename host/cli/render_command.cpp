// `envtrace render`: options -> settings -> a RenderSession (host/lib/session) -> what it wrote.
// Under mpirun every rank runs this; rank 0 speaks for the render and writes its outputs.
#include "commands.h"
#include "progress.h"
#include "render_options.h"
#include "render_print.h"

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

// What --denoise and --live-preview add to the outputs.
void plan_image_extras(const RenderArgs& a, const SessionOptions& so, RenderOutputs& o) {
    if (so.partial && (a.denoise || a.live_preview >= 0))
        throw Error(
            std::string(a.denoise ? "--denoise" : "--live-preview") +
            " works on a whole render's image: a --sample-range task writes none" +
            (a.denoise ? " (render the tasks with --aovs, then 'envtrace merge --denoise')" : ""));
    if (a.live_image && a.live_preview < 0)
        throw Error("--live-image rewrites the image with each live preview: add "
                    "--live-preview SECONDS");
    if (a.live_preview >= 0 && o.preview.empty() && !a.live_image)
        throw Error("--live-preview: this build writes no PNG preview (without OpenImageIO): "
                    "add --live-image to rewrite the linear image instead");
    o.aov_layers = a.aovs;
    if (a.denoise) {
        o.denoised = denoised_name(o.image);
        check_writable_format(o.denoised);
    }
    o.live_interval = a.live_preview;
    o.live_image = a.live_image;
}

// The outputs' names, checked before any time is spent rendering.
RenderOutputs plan_outputs(const RenderArgs& a, const Scene& scene, const SessionOptions& so,
                           bool root) {
    RenderOutputs o;
    std::tie(o.image, o.preview) = output_names(output_name(a, scene, root));
    if (a.aovs && !so.partial && fs::path(o.image).extension() != ".exr")
        throw Error(o.image + ": --aovs writes its layers into an OpenEXR image: name an "
                              ".exr output (-o)");
    check_writable_format(o.image);
    if (!o.preview.empty())
        check_writable_format(o.preview);
    plan_image_extras(a, so, o);
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
    s.outputs = plan_outputs(a, scene, s.options, cl.root());
    if (cl.root())
        check_outputs_possible(s.outputs); // the denoiser, before any time is spent
    s.options.state_path = s.outputs.state;
    s.prepared = prepare_render(std::move(scene), st);
    print_prepared(a.scene, *s.prepared);
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

// Renders on every rank; a first SIGINT/SIGTERM (InterruptHandler) stops the session, which
// keeps the rounds before it, and the outputs are then written under the same handler: a
// second signal ends the process at once, writing nothing more.
SessionResult render(RenderSession& session, const RenderOutputs& outputs, const Cluster& cl) {
    Progress progress(static_cast<int>(session.end() - session.first()),
                      session.settings().time_limit);
    LivePreview live(outputs, session);
    SessionCallbacks cb;
    cb.progress = [&](int done, double seconds) {
        progress.update(done, seconds);
        live.update(done, seconds);
    };
    cb.progress_total = [&](int total) { progress.set_total(total); };
    cb.note = [](const std::string& line) { std::fprintf(stderr, "envtrace: %s\n", line.c_str()); };
    SessionResult r = session.run(cl.root() ? cb : SessionCallbacks{});
    progress.finish();
    return r;
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
    print_start(*s.session, s.build, cl);
    InterruptHandler interrupts;
    const SessionResult r = render(*s.session, s.outputs, cl);
    print_stop(*s.session, s.outputs, r, cl);
    OutputsWritten written;
    cl.check(attempt([&] {
        if (cl.root())
            written = write_outputs(*s.batch, s.outputs, *s.session, r,
                                    render_report({*s.session, r, s.build, cl.size()}));
    }));
    print_summary(*s.session, s.outputs, r, written, total.seconds(), cl);
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
