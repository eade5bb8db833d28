// The extension module `envtrace._envtrace`: the library's errors as envtrace.Error, with the
// message the command line prints, and each concept's bindings. The package around it
// (python/envtrace) is the interface users call.
#include "bindings.h"

#include "session/cluster.h"
#include "util/error.h"

#include <cstring>
#include <memory>

namespace et::py_bind {

py::array_t<float> to_array(std::vector<float>&& data, std::vector<py::ssize_t> shape) {
    auto* owned = new std::vector<float>(std::move(data));
    py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>(shape, owned->data(), free_when_done);
}

py::array_t<float, py::array::c_style | py::array::forcecast>
float_array(const py::handle& a, int ndim, py::ssize_t last, const std::string& what) {
    auto arr = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
    if (!arr)
        throw Error(what + ": expected an array of numbers");
    if (arr.ndim() != ndim || (last > 0 && arr.shape(ndim - 1) != last)) {
        std::string shape;
        for (py::ssize_t d = 0; d < arr.ndim(); ++d)
            shape += (d ? " x " : "") + std::to_string(arr.shape(d));
        throw Error(what + ": expected " + std::to_string(ndim) + " dimensions" +
                    (last > 0 ? ", the last of " + std::to_string(last) : "") + ", got " +
                    (shape.empty() ? "a scalar" : shape));
    }
    return arr;
}

} // namespace et::py_bind

PYBIND11_MODULE(_envtrace, m) {
    namespace py = pybind11;
    m.doc() = "envtrace's library: scenes, renders, images and the map tools (use `envtrace`)";
    static py::exception<et::Error> error(m, "Error");
    // Every failure of the library as envtrace.Error with the command line's message (main.cpp
    // prints the same text after "envtrace: error: "); pybind11's own errors pass through.
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p)
                std::rethrow_exception(p);
        } catch (const py::builtin_exception&) {
            throw;
        } catch (const py::error_already_set&) {
            throw;
        } catch (...) {
            const std::string text = et::error_text();
            PyErr_SetString(error.ptr(), text.c_str());
        }
    });
    m.attr("__version__") = ENVTRACE_VERSION;
    et::py_bind::bind_scene(m);
    et::py_bind::bind_renderer(m);
    et::py_bind::bind_images(m);
    et::py_bind::bind_tools(m);
}
