// Images in and out through the library's readers and writers (OpenImageIO and PFM): every
// channel of a file, a render's layers included, without OpenImageIO's own Python module.
#include "bindings.h"

#include "image/denoise.h"
#include "image/image_io.h"
#include "scene_object.h"
#include "util/error.h"
#include "util/output_batch.h"

#include <pybind11/stl.h>

#include <utility>

namespace et::py_bind {
namespace {

std::pair<std::vector<std::string>, py::array_t<float>> read_channels(const std::string& path) {
    ImageChannels c;
    {
        py::gil_scoped_release free;
        c = read_image_channels(path);
    }
    const auto n = static_cast<py::ssize_t>(c.names.size());
    return {c.names, to_array(std::move(c.pixels), {c.height, c.width, n})};
}

// H x W x C (C channels named by `names`, else 1, 3 or 4 unnamed) or H x W.
void write_channels(const std::string& path, const py::handle& pixels,
                    const std::vector<std::string>& names) {
    auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(pixels);
    if (!a || (a.ndim() != 2 && a.ndim() != 3))
        throw Error(path + ": expected an H x W or H x W x C array of pixels");
    const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
    const int c = a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 1;
    if (!names.empty() && names.size() != static_cast<size_t>(c))
        throw Error(path + ": " + std::to_string(names.size()) + " channel names for " +
                    std::to_string(c) + " channels");
    std::vector<float> data(a.data(), a.data() + a.size());
    py::gil_scoped_release free;
    if (names.empty()) {
        write_image(path, w, h, c, data);
        return;
    }
    OutputBatch batch({path});
    write_image_channels(batch, path, w, h, names, data);
    batch.commit();
}

// The library's denoiser (render --denoise's) on arrays: the guides may be None.
py::array_t<float> denoise_arrays(const py::handle& color, const py::handle& albedo,
                                  const py::handle& normal, bool hdr, bool prefilter) {
    const RgbImage beauty = rgb_image(color, "denoise: color");
    const RgbImage a = albedo.is_none() ? RgbImage{} : rgb_image(albedo, "denoise: albedo");
    const RgbImage n = normal.is_none() ? RgbImage{} : rgb_image(normal, "denoise: normal");
    DenoiseOptions o;
    o.hdr = hdr;
    o.prefilter_guides = prefilter;
    RgbImage out;
    {
        py::gil_scoped_release free;
        out = denoise(beauty, a, n, o);
    }
    return to_array(std::move(out.rgb), {out.height, out.width, 3});
}

} // namespace

void bind_images(py::module_& m) {
    m.def("denoise", &denoise_arrays, py::arg("color"), py::arg("albedo") = py::none(),
          py::arg("normal") = py::none(), py::arg("hdr") = true, py::arg("prefilter") = true,
          "Open Image Denoise's RT filter on an H x W x 3 image, guided by albedo and normal");
    m.def("read_channels", &read_channels, py::arg("path"),
          "Every channel of an image: (names, H x W x C float32 array)");
    m.def("write_channels", &write_channels, py::arg("path"), py::arg("pixels"),
          py::arg("names") = std::vector<std::string>{},
          "Writes an image (all or nothing); named channels make a multi-layer OpenEXR file");
}

} // namespace et::py_bind
