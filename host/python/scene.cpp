// Scenes: loaded from a file or from JSON text with in-memory meshes and maps (the package turns
// a dict scene into these), kept in memory for renderers and their edits.
#include "bindings.h"
#include "scene_object.h"

#include "load/scene_edit.h"
#include "util/error.h"
#include "util/json_file.h"

#include <pybind11/stl.h>

#include <cstring>
#include <filesystem>

namespace et::py_bind {
namespace {

// A mesh given as arrays: "vertices" (N x 3), "indices" (M x 3 integers), optional "normals"
// (N x 3) and "uvs" (N x 2).
MeshArrays mesh_arrays(const py::dict& d, const std::string& where) {
    MeshArrays m;
    const auto v = float_array(d["vertices"], 2, 3, where + ": vertices");
    m.positions.resize(static_cast<size_t>(v.shape(0)));
    std::memcpy(m.positions.data(), v.data(), m.positions.size() * sizeof(glm::vec3));
    auto idx =
        py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(d["indices"]);
    if (!idx || idx.ndim() != 2 || idx.shape(1) != 3)
        throw Error(where + ": indices: expected M x 3 vertex indices");
    m.indices.resize(static_cast<size_t>(idx.size()));
    for (size_t i = 0; i < m.indices.size(); ++i) {
        const int64_t k = idx.data()[i];
        if (k < 0 || k > int64_t(UINT32_MAX))
            throw Error(where + ": triangle " + std::to_string(i / 3) + ": vertex index " +
                        std::to_string(k) + " is out of range (" +
                        std::to_string(m.positions.size()) + " vertices)");
        m.indices[i] = static_cast<uint32_t>(k);
    }
    if (d.contains("normals") && !d["normals"].is_none()) {
        const auto n = float_array(d["normals"], 2, 3, where + ": normals");
        m.normals.resize(static_cast<size_t>(n.shape(0)));
        std::memcpy(m.normals.data(), n.data(), m.normals.size() * sizeof(glm::vec3));
    }
    if (d.contains("uvs") && !d["uvs"].is_none()) {
        const auto t = float_array(d["uvs"], 2, 2, where + ": uvs");
        m.uvs.resize(static_cast<size_t>(t.shape(0)));
        std::memcpy(m.uvs.data(), t.data(), m.uvs.size() * sizeof(glm::vec2));
    }
    return m;
}

PyScene from_json(const std::string& text, const std::string& name, const std::string& dir,
                  const py::dict& meshes, const py::dict& maps) {
    SceneInputs inputs;
    for (auto [key, value] : meshes) {
        const std::string k = py::str(key);
        inputs.meshes[k] = mesh_arrays(py::reinterpret_borrow<py::dict>(value), name + ": " + k);
    }
    for (auto [key, value] : maps) {
        const std::string k = py::str(key);
        inputs.maps[k] = rgb_image(value, name + ": " + k);
    }
    const nlohmann::json j = parse_json_text(name, text);
    PyScene s;
    s.dir = dir;
    {
        py::gil_scoped_release free; // maps' distributions take a while
        s.scene = load_scene_json(j, name, dir, inputs);
    }
    return s;
}

PyScene from_file(const std::string& path) {
    PyScene s;
    s.dir = std::filesystem::path(path).parent_path().string();
    py::gil_scoped_release free;
    s.scene = load_scene(path);
    return s;
}

py::dict environment_of(const PyScene& s) {
    py::dict d;
    d["name"] = s.scene.env.name;
    d["intensity"] = s.scene.env.scale;
    d["rotation"] = s.scene.env.rotation_degrees;
    d["convention"] = name_of(s.scene.env.convention);
    d["width"] = s.scene.env.image.width;
    d["height"] = s.scene.env.image.height;
    return d;
}

} // namespace

void PyScene::edit(const std::string& edit_json, const std::string& where) {
    edit_scene(scene, parse_json_text(where, edit_json), where, dir);
}

RgbImage rgb_image(const py::handle& a, const std::string& what) {
    const auto arr = float_array(a, 3, 3, what);
    RgbImage img;
    img.height = static_cast<int>(arr.shape(0));
    img.width = static_cast<int>(arr.shape(1));
    img.rgb.assign(arr.data(), arr.data() + arr.size());
    return img;
}

void bind_scene(py::module_& m) {
    py::class_<PyScene>(m, "Scene", "A loaded scene: meshes, maps and textures in memory")
        .def_property_readonly("path", [](const PyScene& s) { return s.scene.path; })
        .def_property_readonly("width", [](const PyScene& s) { return s.scene.width; })
        .def_property_readonly("spp", [](const PyScene& s) { return s.scene.settings.spp; })
        .def_property_readonly("height", [](const PyScene& s) { return s.scene.height; })
        .def_property_readonly("triangles",
                               [](const PyScene& s) { return s.scene.triangles.size(); })
        .def_property_readonly("materials",
                               [](const PyScene& s) {
                                   std::vector<std::string> names;
                                   for (const Material& mat : s.scene.materials)
                                       names.push_back(mat.name);
                                   return names;
                               })
        .def_property_readonly("environment", &environment_of)
        .def("edit", &PyScene::edit, py::arg("edit_json"), py::arg("where") = "edit",
             "Applies an edit in the scene file's schema (load/scene_edit.h) to this scene");
    m.def("load_scene", &from_file, py::arg("path"), "Loads a scene file");
    m.def("scene_from_json", &from_json, py::arg("text"), py::arg("name"), py::arg("dir"),
          py::arg("meshes"), py::arg("maps"),
          "A scene from JSON text with in-memory meshes and maps its \"arrays\" keys name");
}

} // namespace et::py_bind
