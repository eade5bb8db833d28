// What the binding's files share: each binds one concept of the library (scene, renderer, images,
// tools) into the module, with numpy arrays for images, meshes and samples.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace et::py_bind {

namespace py = pybind11;

// A float32 array of `shape` that takes over `data` (no copy): C order, as the library's images
// (row-major, row 0 at the top, channels interleaved).
py::array_t<float> to_array(std::vector<float>&& data, std::vector<py::ssize_t> shape);

// A float32, C-contiguous view of `a` (converted where it is not), checked to have `ndim`
// dimensions and, where `last` > 0, that many entries along the last. Throws et::Error naming
// `what`.
py::array_t<float, py::array::c_style | py::array::forcecast>
float_array(const py::handle& a, int ndim, py::ssize_t last, const std::string& what);

void bind_scene(py::module_& m);
void bind_renderer(py::module_& m);
void bind_images(py::module_& m);
void bind_tools(py::module_& m);

} // namespace et::py_bind
