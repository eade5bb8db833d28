// The Renderer: a scene held in memory, rendered progressively on one film (ProgressiveRender),
// edited without reading any file again. An edit restarts the film: the scene's meshes, maps
// (texels and distributions) and textures stay in memory; the device scene (BVH, buffers), the
// strategy's tables and the renderer are made again on the next render.
#include "bindings.h"
#include "interruptible.h"
#include "scene_object.h"

#include "render/film_layers.h"
#include "render/noise_estimate.h"
#include "session/cluster.h"
#include "session/progressive_render.h"
#include "util/error.h"

#include <pybind11/stl.h>

#include <atomic>
#include <csignal>
#include <exception>
#include <memory>
#include <utility>

namespace et::py_bind {
namespace {

// The process's cluster, shared by every renderer: one process (started by mpirun it would be a
// rank, and a progressive render refuses to go on there: RenderSession::extend).
const Cluster& single_process() {
    static Cluster cluster(nullptr, nullptr);
    return cluster;
}

// What the Renderer sets beyond the scene's "render" block: as the command line's options.
struct DeviceOptions {
    std::string backend = "opencl";
    int device = 0, threads = 0;
    bool aovs = false;
};

class PyRenderer {
  public:
    PyRenderer(const PyScene& scene, const DeviceOptions& options)
        : scene_(scene), options_(options) {
        settings(); // bad options fail here, not at the first render
    }

    // `progress`: None, or called as progress(spp, seconds) after each pass kept (on the render's
    // thread, holding the GIL); an exception it raises stops the render and is raised here.
    void render(int spp, const py::object& progress) {
        if (spp < 1 || spp > (1 << 24))
            throw Error("spp " + std::to_string(spp) +
                        ": the film's samples must stay within [1, "
                        "16777216]");
        const Busy busy(*this);
        if (!film_) {
            const RenderSettings st = settings();
            Scene scene = scene_.scene;  // a copy: the edits' base stays
            py::gil_scoped_release free; // preparing takes a while (BVH, strategy tables)
            film_ = std::make_unique<ProgressiveRender>(single_process(), std::move(scene), st,
                                                        scene_.scene.path);
        }
        ProgressiveRender& film = *film_;
        SessionCallbacks cb;
        std::exception_ptr raised;
        if (!progress.is_none())
            cb.progress = [&](int done, double seconds) {
                py::gil_scoped_acquire gil;
                try {
                    progress(done, seconds);
                } catch (const py::error_already_set&) {
                    raised = std::current_exception();
                    film.request_stop(SIGINT);
                }
            };
        run_interruptible([&film, &cb, spp] { film.render_to(spp, cb); },
                          [&film] { film.request_stop(SIGINT); });
        if (raised)
            std::rethrow_exception(raised);
    }

    void edit(const std::string& edit_json, const std::string& where) {
        const Busy busy(*this);
        PyScene edited = scene_; // all or nothing: the settings are checked before it is kept
        edited.edit(edit_json, where);
        settings_of(edited.scene);
        scene_ = std::move(edited);
        film_.reset();
    }

    int spp() const { return film_ ? film_->spp() : 0; }
    const FilmSums& sums() const {
        if (!film_ || film_->spp() == 0)
            throw Error(scene_.scene.path + ": nothing rendered yet (call render first)");
        return film_->result().sums;
    }
    py::array_t<float> image() const {
        const FilmSums& s = sums();
        return to_array(s.mean(), {s.height(), s.width(), 3});
    }
    py::array_t<float> variance() const {
        const FilmSums& s = sums();
        return to_array(s.variance_of_mean(), {s.height(), s.width(), 3});
    }
    std::pair<std::vector<std::string>, py::array_t<float>> layers() const {
        const FilmSums& s = sums();
        FilmLayers l = film_layers(s);
        const auto channels = static_cast<py::ssize_t>(l.names.size());
        return {l.names, to_array(std::move(l.pixels), {s.height(), s.width(), channels})};
    }
    double noise() const { return relative_error(sums()); }
    std::string stats() const {
        sums();
        return report_json(film_->report()).dump();
    }
    const PyScene& scene() const { return scene_; }

  private:
    // A render runs with the GIL released: another Python thread could call in meanwhile, and
    // the film is not to be rendered twice at once or edited under the render.
    struct Busy {
        explicit Busy(PyRenderer& r) : r_(r) {
            if (r_.busy_.exchange(true))
                throw Error(r_.scene_.scene.path + ": the renderer is rendering (in another "
                                                   "thread); one call at a time");
        }
        ~Busy() { r_.busy_ = false; }
        PyRenderer& r_;
    };

    // The scene's settings with the device options, checked as the command line checks them.
    RenderSettings settings() const { return settings_of(scene_.scene); }
    RenderSettings settings_of(const Scene& scene) const {
        RenderSettings st = scene.settings;
        st.backend = parse_backend(options_.backend, "backend");
        st.device = options_.device;
        st.threads = options_.threads;
        st.aovs = options_.aovs;
        if (st.strategy == Strategy::sis)
            throw Error("strategy sis: renders through the command line (envtrace render "
                        "--strategy sis), which sets its strata and depth");
        check_split(st);
        return st;
    }

    PyScene scene_;
    DeviceOptions options_;
    std::unique_ptr<ProgressiveRender> film_; // null: restart on the next render
    std::atomic<bool> busy_{false};
};

} // namespace

void bind_renderer(py::module_& m) {
    py::class_<PyRenderer>(m, "Renderer", "A scene rendered progressively on one film")
        .def(py::init([](const PyScene& scene, const std::string& backend, int device, int threads,
                         bool aovs) {
                 return std::make_unique<PyRenderer>(scene,
                                                     DeviceOptions{backend, device, threads, aovs});
             }),
             py::arg("scene"), py::arg("backend") = "opencl", py::arg("device") = 0,
             py::arg("threads") = 0, py::arg("aovs") = false)
        .def("render", &PyRenderer::render, py::arg("spp"), py::arg("progress") = py::none(),
             "Renders until the film holds spp samples per pixel (Ctrl-C stops, keeping it)")
        .def("edit", &PyRenderer::edit, py::arg("edit_json"), py::arg("where") = "edit",
             "Edits the scene (the scene file's schema) and restarts the film")
        .def_property_readonly("spp", &PyRenderer::spp)
        .def("image", &PyRenderer::image)
        .def("variance", &PyRenderer::variance)
        .def("layers", &PyRenderer::layers)
        .def("noise", &PyRenderer::noise)
        .def("stats", &PyRenderer::stats)
        .def_property_readonly("scene", &PyRenderer::scene);
}

} // namespace et::py_bind
