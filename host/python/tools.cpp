// The paper's tools on a map, as the `sample`, `lights` and `compare` commands use them: samples
// drawn through the map's distribution (directions and densities), the map as N directional
// lights, and image errors against a reference.
#include "bindings.h"
#include "scene_object.h"

#include "image/image_metrics.h"
#include "load/environment_map.h"
#include "prepare/light_set.h"
#include "render/env_sampling.h"
#include "util/error.h"

#include <pybind11/stl.h>

#include <memory>

namespace et::py_bind {
namespace {

DistributionOptions distribution_options(float blur, int width, int height) {
    DistributionOptions o;
    o.blur_sigma = blur;
    o.width = width;
    o.height = height;
    return o;
}

std::shared_ptr<EnvMap> load_map(const std::string& path, float blur, int width, int height) {
    const DistributionOptions o = distribution_options(blur, width, height);
    py::gil_scoped_release free;
    return std::make_shared<EnvMap>(load_envmap(path, o));
}

std::shared_ptr<EnvMap> map_from_array(const py::handle& pixels, const std::string& name,
                                       float blur, int width, int height) {
    RgbImage image = rgb_image(pixels, name);
    const DistributionOptions o = distribution_options(blur, width, height);
    py::gil_scoped_release free;
    return std::make_shared<EnvMap>(make_envmap(name, std::move(image), o));
}

// The first n points of the sampler's sequence (stream 0) through the map's distribution, as
// `envtrace sample` draws them: on the OpenCL device, or natively from the same header.
py::dict sample_map(const EnvMap& env, int n, const std::string& sampler, uint32_t seed,
                    const std::string& backend, int device) {
    if (n < 0 || n > (1 << 24))
        throw Error("sample count " + std::to_string(n) + ": must be within [0, 16777216]");
    const int kind = static_cast<int>(parse_sampler(sampler, "sampler"));
    const Backend b = parse_backend(backend, "backend");
    std::vector<EnvSampleRecord> s;
    {
        py::gil_scoped_release free;
        if (b == Backend::opencl) {
            ClRuntime rt(device);
            EnvSamplerCL cl(rt, env);
            s = cl.sample_sequence(kind, seed, 0, 0, n);
        } else {
            s = sample_env_host_sequence(env, kind, seed, 0, 0, n, 0);
        }
    }
    std::vector<float> dirs(3 * s.size()), pdfs(s.size()), radiance(3 * s.size());
    for (size_t i = 0; i < s.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            dirs[3 * i + k] = s[i].dir[k];
            radiance[3 * i + k] = s[i].radiance[k];
            pdfs[i] = s[i].pdf;
        }
    const auto count = static_cast<py::ssize_t>(s.size());
    py::dict d;
    d["directions"] = to_array(std::move(dirs), {count, 3});
    d["pdfs"] = to_array(std::move(pdfs), {count});
    d["radiance"] = to_array(std::move(radiance), {count, 3});
    return d;
}

// The map as n directional lights, as `envtrace lights` makes them.
std::shared_ptr<LightSet> make_lights(const EnvMap& env, int n, const std::string& method,
                                      uint32_t seed, const std::string& power, int sis_levels) {
    if (n < 1 || n > (1 << 20))
        throw Error("light count " + std::to_string(n) + ": must be within [1, 1048576]");
    if (method != "ours" && method != "sis")
        throw Error("method '" + method + "': use ours or sis");
    if (power != "share" && power != "voronoi")
        throw Error("power '" + power + "': use share or voronoi");
    py::gil_scoped_release free;
    if (method == "ours")
        return std::make_shared<LightSet>(make_lights_ours(env, n, seed, power == "voronoi"));
    SisOptions o;
    o.levels = sis_levels;
    return std::make_shared<LightSet>(make_lights_sis(env, n, o));
}

py::array_t<float> light_directions(const LightSet& set) {
    std::vector<float> d;
    for (const DirectionalLight& l : set.lights)
        d.insert(d.end(), {l.direction.x, l.direction.y, l.direction.z});
    return to_array(std::move(d), {static_cast<py::ssize_t>(set.lights.size()), 3});
}

py::array_t<double> light_powers(const LightSet& set) {
    py::array_t<double> p({static_cast<py::ssize_t>(set.lights.size()), py::ssize_t(3)});
    auto w = p.mutable_unchecked<2>();
    for (size_t i = 0; i < set.lights.size(); ++i)
        for (int k = 0; k < 3; ++k)
            w(static_cast<py::ssize_t>(i), k) = set.lights[i].power[k];
    return p;
}

py::dict compare(const py::handle& a, const py::handle& b, const py::handle& mask) {
    const RgbImage ia = rgb_image(a, "image"), ib = rgb_image(b, "reference");
    std::vector<unsigned char> m;
    if (!mask.is_none()) {
        auto arr = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(mask);
        if (!arr || arr.ndim() != 2 || arr.shape(0) != ia.height || arr.shape(1) != ia.width)
            throw Error("mask: expected an H x W array of the image's size");
        for (py::ssize_t i = 0; i < arr.size(); ++i)
            m.push_back(arr.data()[i] > 0.5f ? 1 : 0);
    }
    const ImageErrors e = compare_images(ia, ib, m);
    py::dict d;
    d["pixels"] = e.pixels;
    d["rmse"] = e.rmse;
    d["rel_mse"] = e.rel_mse;
    d["l2"] = e.l2;
    d["mean"] = e.mean_a;
    d["mean_reference"] = e.mean_b;
    return d;
}

} // namespace

void bind_tools(py::module_& m) {
    py::class_<EnvMap, std::shared_ptr<EnvMap>>(m, "EnvironmentMap",
                                                "A lat-long map with its sampling distribution")
        .def_property_readonly("name", [](const EnvMap& e) { return e.name; })
        .def_property_readonly(
            "pixels",
            [](const EnvMap& e) {
                std::vector<float> px = e.image.rgb;
                return to_array(std::move(px), {e.image.height, e.image.width, 3});
            })
        .def_property_readonly(
            "distribution_size",
            [](const EnvMap& e) { return std::make_pair(e.dist.width, e.dist.height); })
        .def("sample", &sample_map, py::arg("n"), py::arg("sampler") = "sobol", py::arg("seed") = 1,
             py::arg("backend") = "opencl", py::arg("device") = 0)
        .def("lights", &make_lights, py::arg("n"), py::arg("method") = "ours", py::arg("seed") = 1,
             py::arg("power") = "share", py::arg("sis_levels") = 6);
    py::class_<LightSet, std::shared_ptr<LightSet>>(m, "LightSet", "Directional lights of a map")
        .def_property_readonly("method", [](const LightSet& s) { return s.method; })
        .def_property_readonly("power_rule", [](const LightSet& s) { return s.power_rule; })
        .def_property_readonly("directions", &light_directions)
        .def_property_readonly("powers", &light_powers)
        .def_property_readonly(
            "map_power",
            [](const LightSet& s) {
                return std::vector<double>{s.map_power.x, s.map_power.y, s.map_power.z};
            })
        .def("__len__", [](const LightSet& s) { return s.lights.size(); })
        .def(
            "save", [](const LightSet& s, const std::string& path) { write_lights(path, s); },
            py::arg("path"), "Writes the set as `envtrace lights` does (JSON)");
    m.def("load_map", &load_map, py::arg("path"), py::arg("blur") = 0.5f, py::arg("width") = 0,
          py::arg("height") = 0);
    m.def("map_from_array", &map_from_array, py::arg("pixels"), py::arg("name") = "array",
          py::arg("blur") = 0.5f, py::arg("width") = 0, py::arg("height") = 0);
    m.def("compare", &compare, py::arg("image"), py::arg("reference"),
          py::arg("mask") = py::none());
}

} // namespace et::py_bind
