#include "load/scene.h"

#include "util/data_path.h"
#include "util/error.h"
#include "util/json_file.h"
#include "kernels/bsdf.h"
#include "load/scene_environment.h"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <filesystem>
#include <map>

namespace et {
namespace {

using json = nlohmann::json;

struct Reader {
    std::string where; // "scene.json: camera"

    template <typename T> T get(const json& j, const char* key, T fallback) const {
        if (!j.contains(key))
            return fallback;
        try {
            return j.at(key).get<T>();
        } catch (const json::exception&) {
            throw Error(where + ": '" + key + "' has the wrong type (" + j.at(key).dump() + ")");
        }
    }
    float number(const json& j, const char* key, float fallback, float lo, float hi) const {
        float v = get<float>(j, key, fallback);
        if (!std::isfinite(v) || v < lo || v > hi)
            throw Error(where + ": '" + key + "' = " + j.at(key).dump() + " is outside [" +
                        std::to_string(lo) + ", " + std::to_string(hi) + "]");
        return v;
    }
    glm::vec3 vec3(const json& j, const char* key, glm::vec3 fallback) const {
        if (!j.contains(key))
            return fallback;
        const json& a = j.at(key);
        if (a.is_number()) {
            float s = a.get<float>();
            return glm::vec3(s);
        }
        if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() ||
            !a[2].is_number())
            throw Error(where + ": '" + key + "' must be [x, y, z] (got " + a.dump() + ")");
        glm::vec3 v(a[0].get<float>(), a[1].get<float>(), a[2].get<float>());
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
            throw Error(where + ": '" + key + "' is not finite");
        return v;
    }
};

glm::mat4 read_transform(const json& s, const Reader& r) {
    glm::mat4 m(1.0f);
    if (!s.contains("transform"))
        return m;
    const json& t = s["transform"];
    Reader rt{r.where + ".transform"};
    warn_unknown_keys(t, {"translate", "rotate", "scale", "matrix"}, rt.where);
    if (t.contains("matrix")) {
        // A full 4x4 matrix, row-major (as Mitsuba writes them); nothing else alongside it.
        const json& a = t["matrix"];
        if (!a.is_array() || a.size() != 16)
            throw Error(rt.where + ": 'matrix' must be 16 numbers, row-major");
        if (t.size() != 1)
            throw Error(rt.where + ": 'matrix' cannot be combined with translate/rotate/scale");
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) {
                if (!a[4 * r + c].is_number())
                    throw Error(rt.where + ": 'matrix' must be 16 numbers, row-major");
                m[c][r] = a[4 * r + c].get<float>(); // glm is column-major
            }
        if (!(std::fabs(glm::determinant(glm::mat3(m))) > 0.0f))
            throw Error(rt.where + ": 'matrix' is singular");
        return m;
    }
    // Applied as scale, then rotate (about [x, y, z] by degrees), then translate.
    m = glm::translate(m, rt.vec3(t, "translate", glm::vec3(0.0f)));
    if (t.contains("rotate")) {
        const json& a = t["rotate"];
        if (!a.is_array() || a.size() != 4)
            throw Error(rt.where + ": 'rotate' must be [axis x, axis y, axis z, degrees]");
        glm::vec3 axis(a[0].get<float>(), a[1].get<float>(), a[2].get<float>());
        if (!(glm::length(axis) > 0.0f))
            throw Error(rt.where + ": 'rotate' axis is zero");
        m = glm::rotate(m, glm::radians(a[3].get<float>()), glm::normalize(axis));
    }
    glm::vec3 sc = rt.vec3(t, "scale", glm::vec3(1.0f));
    if (sc.x == 0.0f || sc.y == 0.0f || sc.z == 0.0f)
        throw Error(rt.where + ": 'scale' has a zero component");
    return glm::scale(m, sc);
}

void add_sphere(TriangleSoup& soup, glm::vec3 c, float radius, int segments, int material) {
    const int rings = std::max(2, segments / 2);
    auto point = [&](int i, int j) {
        float th = float(M_PI) * i / rings, ph = 2.0f * float(M_PI) * j / segments;
        return glm::vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
    };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            glm::vec3 n00 = point(i, j), n01 = point(i, j + 1), n10 = point(i + 1, j),
                      n11 = point(i + 1, j + 1);
            glm::vec3 a[3] = {n00, n01, n11}, b[3] = {n00, n11, n10};
            for (auto* tri : {a, b}) {
                glm::vec3 p[3] = {c + radius * tri[0], c + radius * tri[1], c + radius * tri[2]};
                add_triangle(soup, p, tri, material);
            }
        }
}

Material read_material(const std::string& name, const json& j, const Reader& r) {
    Material m;
    m.name = name;
    warn_unknown_keys(j, {"type", "albedo", "specular", "roughness"}, r.where);
    const std::string type = r.get<std::string>(j, "type", "diffuse");
    if (type == "diffuse") {
        m.type = ETK_MAT_DIFFUSE;
    } else if (type == "microfacet" || type == "plastic" || type == "cook-torrance") {
        m.type = ETK_MAT_MICROFACET;
        m.specular = glm::vec3(0.04f);
        m.albedo = glm::vec3(type == "plastic" ? 0.5f : 0.0f);
    } else if (type == "mirror") {
        m.type = ETK_MAT_MIRROR;
        m.specular = glm::vec3(1.0f);
    } else {
        throw Error(r.where + ": unknown material type '" + type +
                    "' (use diffuse, microfacet, plastic or mirror)");
    }
    m.albedo = glm::clamp(r.vec3(j, "albedo", m.albedo), 0.0f, 1.0f);
    m.specular = glm::clamp(r.vec3(j, "specular", m.specular), 0.0f, 1.0f);
    m.roughness = r.number(j, "roughness", m.roughness, 0.0f, 1.0f);
    return m;
}

} // namespace

Scene load_scene(const std::string& path) {
    json j = read_json_file(path);
    if (!j.is_object())
        throw Error(path + ": the scene must be a JSON object");
    Scene scene;
    scene.path = path;
    const std::string dir = std::filesystem::path(path).parent_path().string();
    Reader r{path};
    warn_unknown_keys(
        j, {"camera", "film", "environment", "materials", "shapes", "render", "output"}, path);

    if (j.contains("camera")) {
        Reader rc{path + ": camera"};
        const json& c = j["camera"];
        warn_unknown_keys(c, {"eye", "target", "up", "fov"}, rc.where);
        scene.camera.eye = rc.vec3(c, "eye", scene.camera.eye);
        scene.camera.target = rc.vec3(c, "target", scene.camera.target);
        scene.camera.up = rc.vec3(c, "up", scene.camera.up);
        scene.camera.fov_deg = rc.number(c, "fov", scene.camera.fov_deg, 0.01f, 179.0f);
        glm::vec3 f = scene.camera.target - scene.camera.eye;
        if (!(glm::length(f) > 0.0f) ||
            !(glm::length(glm::cross(f, scene.camera.up)) > 1e-6f * glm::length(f)))
            throw Error(
                rc.where +
                ": eye, target and up must span a view (eye != target, up not along the view)");
    }
    if (j.contains("film")) {
        Reader rf{path + ": film"};
        warn_unknown_keys(j["film"], {"width", "height"}, rf.where);
        scene.width = static_cast<int>(rf.number(j["film"], "width", 512, 1, 16384));
        scene.height = static_cast<int>(rf.number(j["film"], "height", 512, 1, 16384));
    }
    if (j.contains("render")) {
        Reader rr{path + ": render"};
        const json& s = j["render"];
        warn_unknown_keys(
            s,
            {"spp", "max_depth", "strategy", "heuristic", "sampler", "seed", "time_limit", "paths"},
            rr.where);
        auto& st = scene.settings;
        st.spp = static_cast<int>(rr.number(s, "spp", st.spp, 1, 1 << 24));
        st.max_depth = static_cast<int>(rr.number(s, "max_depth", st.max_depth, 1, 1000));
        if (s.contains("strategy"))
            st.strategy = parse_strategy(rr.get<std::string>(s, "strategy", ""), rr.where);
        if (s.contains("heuristic"))
            st.heuristic = parse_heuristic(rr.get<std::string>(s, "heuristic", ""), rr.where);
        if (s.contains("sampler"))
            st.sampler = parse_sampler(rr.get<std::string>(s, "sampler", ""), rr.where);
        st.seed = rr.get<uint32_t>(s, "seed", st.seed);
        st.time_limit = rr.number(s, "time_limit", 0.0f, 0.0f, 1e7f);
        st.paths = static_cast<int>(rr.number(s, "paths", 0, 0, 1 << 26));
    }
    scene.output = r.get<std::string>(j, "output", "");

    if (!j.contains("environment"))
        throw Error(path + ": no \"environment\": a scene needs a map or a sky to be lit by");
    scene.env = load_scene_environment(j["environment"], dir, path, {});

    std::map<std::string, int> by_name;
    if (j.contains("materials")) {
        if (!j["materials"].is_object())
            throw Error(path + ": materials must be an object of name: {type, ...}");
        for (auto it = j["materials"].begin(); it != j["materials"].end(); ++it) {
            by_name[it.key()] = static_cast<int>(scene.materials.size());
            scene.materials.push_back(
                read_material(it.key(), it.value(), Reader{path + ": materials." + it.key()}));
        }
    }
    auto material_of = [&](const json& s, const Reader& rs) {
        if (!s.contains("material"))
            return -1;
        std::string name = rs.get<std::string>(s, "material", "");
        auto it = by_name.find(name);
        if (it == by_name.end())
            throw Error(rs.where + ": material '" + name + "' is not defined in \"materials\"");
        return it->second;
    };
    auto default_material = [&] {
        if (!by_name.count("__default")) {
            by_name["__default"] = static_cast<int>(scene.materials.size());
            Material m;
            m.name = "default";
            scene.materials.push_back(m);
        }
        return by_name["__default"];
    };

    if (j.contains("shapes")) {
        if (!j["shapes"].is_array())
            throw Error(path + ": shapes must be an array");
        int index = 0;
        for (const json& s : j["shapes"]) {
            Reader rs{path + ": shapes[" + std::to_string(index++) + "]"};
            if (!s.is_object())
                throw Error(rs.where + ": each shape must be an object");
            const std::string type = rs.get<std::string>(s, "type", "");
            int mat = material_of(s, rs);
            if (type == "mesh") {
                warn_unknown_keys(s, {"type", "file", "material", "transform"}, rs.where);
                std::string file = resolve_data_file(rs.get<std::string>(s, "file", ""), dir);
                load_obj(file, read_transform(s, rs), mat, scene.materials, scene.triangles);
            } else if (type == "sphere") {
                warn_unknown_keys(s, {"type", "center", "radius", "material", "segments", "smooth"},
                                  rs.where);
                glm::vec3 c = rs.vec3(s, "center", glm::vec3(0.0f));
                float radius = rs.number(s, "radius", 1.0f, 1e-6f, 1e9f);
                int segments = static_cast<int>(rs.number(s, "segments", 96, 4, 4096));
                TriangleSoup sphere;
                add_sphere(sphere, c, radius, segments, mat < 0 ? default_material() : mat);
                if (!rs.get<bool>(s, "smooth", true))
                    for (size_t t = 0; t < sphere.size(); ++t) {
                        glm::vec3 ng = glm::normalize(
                            glm::cross(sphere.positions[3 * t + 1] - sphere.positions[3 * t],
                                       sphere.positions[3 * t + 2] - sphere.positions[3 * t]));
                        for (int k = 0; k < 3; ++k)
                            sphere.normals[3 * t + k] = ng;
                    }
                auto& T = scene.triangles;
                T.positions.insert(T.positions.end(), sphere.positions.begin(),
                                   sphere.positions.end());
                T.normals.insert(T.normals.end(), sphere.normals.begin(), sphere.normals.end());
                T.material.insert(T.material.end(), sphere.material.begin(), sphere.material.end());
            } else if (type == "quad") {
                warn_unknown_keys(s, {"type", "center", "size", "material", "transform"}, rs.where);
                glm::vec3 c = rs.vec3(s, "center", glm::vec3(0.0f));
                float hx = 5.0f, hz = 5.0f; // "size": edge length or [x extent, z extent]
                if (s.contains("size")) {
                    const json& z = s["size"];
                    if (z.is_number() && z.get<float>() > 0.0f)
                        hx = hz = 0.5f * z.get<float>();
                    else if (z.is_array() && z.size() == 2 && z[0].is_number() &&
                             z[1].is_number() && z[0].get<float>() > 0.0f &&
                             z[1].get<float>() > 0.0f) {
                        hx = 0.5f * z[0].get<float>();
                        hz = 0.5f * z[1].get<float>();
                    } else
                        throw Error(rs.where + ": 'size' must be a positive number or [x, z]");
                }
                glm::mat4 m = read_transform(s, rs);
                glm::vec3 q[4] = {{-hx, 0, -hz}, {hx, 0, -hz}, {hx, 0, hz}, {-hx, 0, hz}};
                for (auto& v : q)
                    v = glm::vec3(m * glm::vec4(c + v, 1.0f));
                glm::vec3 a[3] = {q[0], q[2], q[1]}, b[3] = {q[0], q[3], q[2]};
                int qm = mat < 0 ? default_material() : mat;
                if (!add_triangle(scene.triangles, a, nullptr, qm) ||
                    !add_triangle(scene.triangles, b, nullptr, qm))
                    throw Error(rs.where + ": the quad is degenerate");
            } else {
                throw Error(rs.where + ": unknown shape type '" + type +
                            "' (use mesh, sphere or quad)");
            }
        }
    }
    if (scene.triangles.size() == 0)
        warn(path + ": the scene has no geometry; rendering the environment alone");
    return scene;
}

} // namespace et
