#include "load/scene.h"

#include "util/data_path.h"
#include "util/error.h"
#include "util/json_file.h"
#include "util/checked_size.h"
#include "kernels/bsdf.h"
#include "load/scene_blocks.h"
#include "load/scene_environment.h"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>

namespace et {
namespace {

using json = nlohmann::json;

// Colours and vectors: [x, y, z] of finite floats, or one number for all three.
glm::vec3 read_vec3(const json& j, const char* key, glm::vec3 fallback, const JsonReader& r,
                    bool allow_scalar = true) {
    auto it = j.find(key);
    if (it == j.end())
        return fallback;
    const JsonReader rk = r.at(key);
    const double big = std::numeric_limits<float>::max();
    if (allow_scalar && it->is_number())
        return glm::vec3(static_cast<float>(rk.number(*it, -big, big)));
    if (!it->is_array() || it->size() != 3)
        rk.fail(std::string("expected [x, y, z]") + (allow_scalar ? " or one number" : "") +
                ", got " + json_excerpt(*it));
    glm::vec3 v;
    for (int k = 0; k < 3; ++k)
        v[k] = static_cast<float>(rk.at(k).number((*it)[k], -big, big));
    return v;
}

float read_float(const json& j, const char* key, float fallback, float lo, float hi,
                 const JsonReader& r) {
    return static_cast<float>(r.number(j, key, fallback, lo, hi));
}

int read_int(const json& j, const char* key, int fallback, int lo, int hi, const JsonReader& r) {
    return static_cast<int>(r.integer(j, key, fallback, lo, hi));
}

glm::mat4 read_transform(const json& s, const JsonReader& r) {
    glm::mat4 m(1.0f);
    const json* tp = r.object(s, "transform");
    if (!tp)
        return m;
    const json& t = *tp;
    const JsonReader rt = r.at("transform");
    rt.reject_unknown_keys(t, {"translate", "rotate", "scale", "matrix"});
    const double big = 1e30;
    if (t.contains("matrix")) {
        // A full 4x4 matrix, row-major (as Mitsuba writes them); nothing else alongside it.
        const json& a = t["matrix"];
        const JsonReader rm = rt.at("matrix");
        if (!a.is_array() || a.size() != 16)
            rm.fail("expected 16 numbers, row-major, got " + json_excerpt(a));
        if (t.size() != 1)
            rm.fail("cannot be combined with translate/rotate/scale");
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) // glm is column-major
                m[c][r] = static_cast<float>(rm.at(4 * r + c).number(a[4 * r + c], -big, big));
        // Only affine transforms: a mesh is moved, not projected. A bottom row other than
        // [0, 0, 0, 1] is most often a column-major matrix pasted here (its translation in the last
        // row), which would otherwise lose its translation without a word.
        // (Within 1e-6: a float or numpy round-off there is harmless; a pasted translation is not.)
        if (std::fabs(m[0][3]) > 1e-6f || std::fabs(m[1][3]) > 1e-6f ||
            std::fabs(m[2][3]) > 1e-6f || std::fabs(m[3][3] - 1.0f) > 1e-6f)
            rm.fail("the last row must be [0, 0, 0, 1] (an affine transform, row-major: the "
                    "translation is the last column), got [" +
                    json_excerpt(a[12]) + ", " + json_excerpt(a[13]) + ", " + json_excerpt(a[14]) +
                    ", " + json_excerpt(a[15]) + "]");
        m[0][3] = m[1][3] = m[2][3] = 0.0f; // exactly affine
        m[3][3] = 1.0f;
        const float det = glm::determinant(glm::mat3(m));
        if (!(std::fabs(det) > 0.0f) || !std::isfinite(det))
            rm.fail("is singular (or its determinant overflows)");
        return m;
    }
    // Applied as scale, then rotate (about [x, y, z] by degrees), then translate.
    glm::vec3 tr = read_vec3(t, "translate", glm::vec3(0.0f), rt, false);
    if (glm::any(glm::greaterThan(glm::abs(tr), glm::vec3(big))))
        rt.at("translate").fail("components must be within [-1e30, 1e30]");
    m = glm::translate(m, tr);
    if (t.contains("rotate")) {
        const json& a = t["rotate"];
        const JsonReader ra = rt.at("rotate");
        if (!a.is_array() || a.size() != 4)
            ra.fail("expected [axis x, axis y, axis z, degrees], got " + json_excerpt(a));
        glm::vec3 axis;
        for (int k = 0; k < 3; ++k)
            axis[k] = static_cast<float>(ra.at(k).number(a[k], -big, big));
        const float degrees = static_cast<float>(ra.at(3).number(a[3], -1e6, 1e6));
        const float len = glm::length(axis);
        if (!(len > 0.0f) || !std::isfinite(len))
            ra.fail("the axis is zero or too long");
        m = glm::rotate(m, glm::radians(degrees), axis / len);
    }
    glm::vec3 sc = read_vec3(t, "scale", glm::vec3(1.0f), rt);
    if (sc.x == 0.0f || sc.y == 0.0f || sc.z == 0.0f)
        rt.at("scale").fail("has a zero component");
    if (glm::any(glm::greaterThan(glm::abs(sc), glm::vec3(big))))
        rt.at("scale").fail("components must be within [-1e30, 1e30]");
    return glm::scale(m, sc);
}

// Returns the triangles dropped as degenerate (a sphere too small for float at its centre).
size_t add_sphere(TriangleSoup& soup, glm::vec3 c, float radius, int segments, int material) {
    size_t dropped = 0;
    const int rings = std::max(2, segments / 2);
    // A closed surface: the last column is the first one again and the poles are single points
    // (in float, sin(pi) and sin(2 pi) are not 0, which left a slit along the seam and a ring at
    // the bottom pole that rays passed through). Each vertex is computed once, in double, so
    // that the triangles around it share its bits.
    auto point = [&](int i, int j) {
        if (i == 0 || i == rings)
            return glm::vec3(0.0f, i == 0 ? 1.0f : -1.0f, 0.0f);
        j %= segments;
        const double th = M_PI * i / rings, ph = 2.0 * M_PI * j / segments;
        return glm::vec3(
            glm::dvec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)));
    };
    // Texture coordinates: u around the axis (from +X towards +Z), v = 1 at the top pole.
    auto uv = [&](int i, int j) { return glm::vec2(float(j) / segments, 1.0f - float(i) / rings); };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            glm::vec3 n00 = point(i, j), n01 = point(i, j + 1), n10 = point(i + 1, j),
                      n11 = point(i + 1, j + 1);
            glm::vec3 a[3] = {n00, n01, n11}, b[3] = {n00, n11, n10};
            glm::vec2 ta[3] = {uv(i, j), uv(i, j + 1), uv(i + 1, j + 1)},
                      tb[3] = {uv(i, j), uv(i + 1, j + 1), uv(i + 1, j)};
            glm::vec3 pa[3] = {c + radius * a[0], c + radius * a[1], c + radius * a[2]},
                      pb[3] = {c + radius * b[0], c + radius * b[1], c + radius * b[2]};
            // The first ring's a and the last's b have two corners at a pole: not triangles.
            if (i > 0)
                dropped += !add_triangle(soup, pa, a, material, ta);
            if (i < rings - 1)
                dropped += !add_triangle(soup, pb, b, material, tb);
        }
    return dropped;
}

// The coordinate range the kernels' float arithmetic holds, for messages: "[-1e+12, 1e+12]".
std::string scene_range_text() {
    char buf[64];
    std::snprintf(buf, sizeof buf, "[-%g, %g]", double(kMaxSceneCoordinate),
                  double(kMaxSceneCoordinate));
    return buf;
}

// A point the kernels' float arithmetic holds (kMaxSceneCoordinate): a camera eye, a shape's
// centre.
void require_in_range(const glm::vec3& v, const JsonReader& r) {
    if (glm::any(glm::greaterThan(glm::abs(v), glm::vec3(kMaxSceneCoordinate))))
        r.fail("components must be within " + scene_range_text() +
               " (float ray tests; scale the scene down)");
}

} // namespace

Material read_material(const std::string& name, const json& j, const JsonReader& r,
                       const std::string& dir, TextureSet& textures) {
    Material m;
    m.name = name;
    r.expect_object(j);
    r.reject_unknown_keys(j,
                          {"type", "albedo", "specular", "roughness", "ior", "tint", "eta", "k"});
    const std::string type = r.string(j, "type", "diffuse");
    if (type == "diffuse") {
        m.type = ETK_MAT_DIFFUSE;
    } else if (type == "microfacet" || type == "plastic" || type == "cook-torrance") {
        m.type = ETK_MAT_MICROFACET;
        m.specular = glm::vec3(0.04f);
        m.albedo = glm::vec3(type == "plastic" ? 0.5f : 0.0f);
    } else if (type == "mirror") {
        m.type = ETK_MAT_MIRROR;
        m.specular = glm::vec3(1.0f);
    } else if (type == "dielectric" || type == "glass") {
        // Glass: roughness 0 (the default) is the smooth interface, else a GGX one; "tint"
        // colours the transmission at each crossing.
        m.type = ETK_MAT_DIELECTRIC;
        m.roughness = read_float(j, "roughness", 0.0f, 0.0f, 1.0f, r);
        if (m.roughness < 1e-3f) // the GGX alpha's floor (bsdf.h): below it, a delta lobe
            m.type = ETK_MAT_SMOOTH_DIELECTRIC;
        m.ior = read_float(j, "ior", 1.5f, 0.25f, 4.0f, r);
        m.albedo = glm::clamp(read_vec3(j, "tint", glm::vec3(1.0f), r), 0.0f, 1.0f);
        for (const char* key : {"albedo", "specular", "eta", "k"})
            if (j.contains(key))
                r.at(key).fail(std::string("a dielectric has no ") + key +
                               " (use \"tint\" for a coloured transmission, \"ior\", "
                               "\"roughness\")");
        return m;
    } else if (type == "conductor" || type == "metal") {
        // A metal: the GGX lobe with the Fresnel reflectance of a complex index eta + i k per
        // channel (bsdf.h); the defaults (scene.h) are silver's. Its roughness is read below.
        m.type = ETK_MAT_CONDUCTOR;
        m.roughness = 0.1f;
        auto index = [&](const char* key, glm::vec3 v, float lo, const char* range) {
            v = read_vec3(j, key, v, r);
            if (glm::any(glm::lessThan(v, glm::vec3(lo))) ||
                glm::any(glm::greaterThan(v, glm::vec3(100.0f))))
                r.at(key).fail(std::string("each component must be within ") + range);
            return v;
        };
        m.eta = index("eta", m.eta, 0.01f, "[0.01, 100]");
        m.k = index("k", m.k, 0.0f, "[0, 100]");
        for (const char* key : {"albedo", "specular"})
            if (j.contains(key))
                r.at(key).fail(std::string("a conductor has no \"") + key +
                               "\" (its colour is its complex index: \"eta\" and \"k\", per "
                               "channel; and \"roughness\")");
    } else {
        r.at("type").fail("unknown material type " + json_excerpt(j["type"]) +
                          " (use diffuse, microfacet, plastic, conductor, mirror or dielectric)");
    }
    for (const char* key : {"ior", "tint"})
        if (j.contains(key))
            r.at(key).fail(std::string("only a dielectric material has \"") + key + "\"");
    for (const char* key : {"eta", "k"})
        if (m.type != ETK_MAT_CONDUCTOR && j.contains(key))
            r.at(key).fail(std::string("only a conductor material has \"") + key + "\"");
    // Keys the type has no use for: a "diffuse" given a specular colour or a roughness, a mirror
    // given a roughness or an albedo, rendered as if they were absent, without a word.
    for (const char* key : {"specular", "roughness"})
        if (m.type == ETK_MAT_DIFFUSE && j.contains(key))
            r.at(key).fail(std::string("a diffuse material has no \"") + key +
                           "\" (a glossy lobe over a diffuse base is \"plastic\" or "
                           "\"microfacet\" with an \"albedo\")");
    for (const char* key : {"albedo", "roughness"})
        if (m.type == ETK_MAT_MIRROR && j.contains(key))
            r.at(key).fail(std::string("a mirror has no \"") + key +
                           "\" (its colour is \"specular\"; a rough mirror is \"conductor\" or "
                           "\"microfacet\" with a \"roughness\")");
    // Each may be a texture instead of a constant (load/texture.h).
    m.albedo_tex = read_texture_param(j, "albedo", TextureUse::colour, dir, r, textures);
    m.specular_tex = read_texture_param(j, "specular", TextureUse::colour, dir, r, textures);
    m.roughness_tex = read_texture_param(j, "roughness", TextureUse::data, dir, r, textures);
    if (m.albedo_tex < 0)
        m.albedo = glm::clamp(read_vec3(j, "albedo", m.albedo, r), 0.0f, 1.0f);
    if (m.specular_tex < 0)
        m.specular = glm::clamp(read_vec3(j, "specular", m.specular, r), 0.0f, 1.0f);
    if (m.roughness_tex < 0)
        m.roughness = read_float(j, "roughness", m.roughness, 0.0f, 1.0f, r);
    return m;
}

Camera read_camera(const json& c, const JsonReader& rc, Camera camera) {
    rc.reject_unknown_keys(c, {"eye", "target", "up", "fov"});
    camera.eye = read_vec3(c, "eye", camera.eye, rc, false);
    camera.target = read_vec3(c, "target", camera.target, rc, false);
    camera.up = read_vec3(c, "up", camera.up, rc, false);
    camera.fov_deg = read_float(c, "fov", camera.fov_deg, 0.01f, 179.0f, rc);
    for (const glm::vec3& v : {camera.eye, camera.target, camera.up})
        if (glm::any(glm::greaterThan(glm::abs(v), glm::vec3(1e30f))))
            rc.fail("eye, target and up must be within [-1e30, 1e30]");
    require_in_range(camera.eye, rc.at("eye"));
    glm::vec3 f = camera.target - camera.eye;
    if (!(glm::length(f) > 0.0f) ||
        !(glm::length(glm::cross(f, camera.up)) > 1e-6f * glm::length(f)))
        rc.fail("eye, target and up must span a view (eye != target, up not along the view)");
    return camera;
}

void read_render_block(const json& s, const JsonReader& rr, RenderSettings& st) {
    rr.reject_unknown_keys(s, {"spp", "max_depth", "strategy", "heuristic", "sampler", "seed",
                               "time_limit", "paths", "bsdf_sampling", "light_samples",
                               "bsdf_samples", "rr_depth"});
    st.spp = read_int(s, "spp", st.spp, 1, 1 << 24, rr);
    st.max_depth = read_int(s, "max_depth", st.max_depth, 1, 1000, rr);
    st.rr_depth = read_int(s, "rr_depth", st.rr_depth, 0, 1000, rr);
    if (s.contains("strategy"))
        st.strategy = parse_strategy(rr.string(s, "strategy", ""), rr.at("strategy").where());
    if (s.contains("heuristic"))
        st.heuristic = parse_heuristic(rr.string(s, "heuristic", ""), rr.at("heuristic").where());
    if (s.contains("sampler"))
        st.sampler = parse_sampler(rr.string(s, "sampler", ""), rr.at("sampler").where());
    if (s.contains("bsdf_sampling"))
        st.bsdf_sampling =
            parse_bsdf_sampling(rr.string(s, "bsdf_sampling", ""), rr.at("bsdf_sampling").where());
    st.seed = static_cast<uint32_t>(rr.integer(s, "seed", st.seed, 0, 4294967295LL));
    st.time_limit = rr.number(s, "time_limit", st.time_limit, 0.0, 1e7);
    st.paths = read_int(s, "paths", st.paths, 0, 1 << 26, rr);
    st.light_samples =
        check_split_count(read_int(s, "light_samples", st.light_samples, 1, ETK_MAX_SPLIT, rr),
                          rr.at("light_samples").where());
    st.bsdf_samples =
        check_split_count(read_int(s, "bsdf_samples", st.bsdf_samples, 1, ETK_MAX_SPLIT, rr),
                          rr.at("bsdf_samples").where());
}

Scene load_scene(const std::string& path) {
    const json j = read_json_file(path, "scene file");
    return load_scene_json(j, path, std::filesystem::path(path).parent_path().string());
}

Scene load_scene_json(const json& j, const std::string& path, const std::string& dir,
                      const SceneInputs& inputs) {
    const JsonReader r(path);
    if (!j.is_object())
        r.fail("the scene must be a JSON object, got " + json_excerpt(j));
    Scene scene;
    scene.path = path;
    r.reject_unknown_keys(
        j, {"camera", "film", "environment", "materials", "shapes", "render", "output"});

    if (const json* cp = r.object(j, "camera"))
        scene.camera = read_camera(*cp, r.at("camera"), scene.camera);
    if (const json* fp = r.object(j, "film")) {
        const JsonReader rf = r.at("film");
        rf.reject_unknown_keys(*fp, {"width", "height"});
        scene.width = read_int(*fp, "width", scene.width, 1, 16384, rf);
        scene.height = read_int(*fp, "height", scene.height, 1, 16384, rf);
    }
    if (const json* sp = r.object(j, "render"))
        read_render_block(*sp, r.at("render"), scene.settings);
    scene.output = r.string(j, "output", "");
    if (j.contains("output") && scene.output.empty()) // as an empty map is
        r.at("output").fail("is empty: name the image to write (.exr, .hdr or .pfm), or leave "
                            "the key out");

    if (!j.contains("environment"))
        r.fail("no \"environment\": a scene needs a map or a sky to be lit by");
    scene.env = load_scene_environment(j["environment"], dir, path, {}, &inputs.maps);

    std::map<std::string, int> by_name;
    if (const json* mp = r.object(j, "materials")) {
        const JsonReader rm = r.at("materials");
        for (auto it = mp->begin(); it != mp->end(); ++it) {
            by_name[it.key()] = static_cast<int>(scene.materials.size());
            scene.materials.push_back(
                read_material(it.key(), it.value(), rm.at(it.key()), dir, scene.textures));
        }
    }
    auto material_of = [&](const json& s, const JsonReader& rs) {
        if (!s.contains("material"))
            return -1;
        std::string name = rs.string(s, "material", "");
        auto it = by_name.find(name);
        if (it == by_name.end())
            rs.at("material")
                .fail("material " + json_excerpt(s["material"]) +
                      " is not defined in \"materials\"");
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
        const JsonReader rshapes = r.at("shapes");
        rshapes.expect_array(j["shapes"]);
        size_t index = 0;
        for (const json& s : j["shapes"]) {
            const JsonReader rs = rshapes.at(index++);
            rs.expect_object(s);
            if (!s.contains("type"))
                rs.fail("no \"type\" (use mesh, sphere or quad)");
            const std::string type = rs.string(s, "type", "");
            int mat = material_of(s, rs);
            if (type == "mesh") {
                rs.reject_unknown_keys(s, {"type", "file", "arrays", "material", "transform"});
                const glm::mat4 transform = read_transform(s, rs);
                if (s.contains("arrays")) {
                    if (s.contains("file"))
                        rs.fail("has both \"file\" and \"arrays\": give one");
                    const std::string name = rs.string(s, "arrays", "");
                    const auto it = inputs.meshes.find(name);
                    if (it == inputs.meshes.end())
                        rs.at("arrays").fail("names no mesh given in memory with the scene");
                    append_mesh_arrays(it->second, rs.where(), transform, mat, scene.materials,
                                       scene.triangles);
                    continue;
                }
                if (!s.contains("file"))
                    rs.fail("a mesh needs \"file\" (an OBJ, PLY, glTF or GLB file)");
                std::string file = resolve_data_file(rs.string(s, "file", ""), dir);
                load_mesh(file, transform, mat, scene.materials, scene.triangles, &scene.textures);
            } else if (type == "sphere") {
                rs.reject_unknown_keys(
                    s, {"type", "center", "radius", "material", "segments", "smooth"});
                glm::vec3 c = read_vec3(s, "center", glm::vec3(0.0f), rs, false);
                require_in_range(c, rs.at("center"));
                float radius = read_float(s, "radius", 1.0f, 1e-6f, 1e9f, rs);
                int segments = read_int(s, "segments", 96, 4, 4096, rs);
                const bool smooth = rs.boolean(s, "smooth", true);
                // Vertices are floats in the scene's coordinates: at a centre far from the
                // origin they are rounded to its ulp, and a small sphere flattens or collapses.
                const float far = std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)});
                const double steps =
                    far > 0.0f ? radius / (std::nextafter(far, 2.0f * far) - far) : 1e30;
                if (steps < 8.0)
                    rs.at("radius").fail(
                        "the sphere is too small to be resolved in float at its centre (its "
                        "vertices round to steps of " +
                        std::to_string(radius / steps) +
                        "); scale the scene or move it towards the origin");
                if (steps < 1024.0)
                    warn(rs.where() + ": the sphere's vertices round to 1/" +
                         std::to_string(int(steps)) +
                         " of its radius at its centre: a faceted surface (scale the scene or "
                         "move it towards the origin)");
                TriangleSoup sphere;
                const size_t dropped =
                    add_sphere(sphere, c, radius, segments, mat < 0 ? default_material() : mat);
                if (dropped) // corners float cannot tell apart
                    warn(rs.where() + ": " + std::to_string(dropped) + " of " +
                         std::to_string(sphere.size() + dropped) +
                         " triangles collapse in float (radius too small for its centre) and "
                         "are skipped");
                if (!smooth)
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
                T.uvs.resize(3 * (T.size() - sphere.size()), glm::vec2(0.0f));
                T.uvs.insert(T.uvs.end(), sphere.uvs.begin(), sphere.uvs.end());
            } else if (type == "quad") {
                rs.reject_unknown_keys(s, {"type", "center", "size", "material", "transform"});
                glm::vec3 c = read_vec3(s, "center", glm::vec3(0.0f), rs, false);
                require_in_range(c, rs.at("center"));
                float hx = 5.0f, hz = 5.0f; // "size": edge length or [x extent, z extent]
                if (s.contains("size")) {
                    const json& z = s["size"];
                    const JsonReader rz = rs.at("size");
                    if (z.is_array() && z.size() == 2) {
                        hx = 0.5f * static_cast<float>(rz.at(0).number(z[0], 1e-9, 1e30));
                        hz = 0.5f * static_cast<float>(rz.at(1).number(z[1], 1e-9, 1e30));
                    } else if (z.is_number()) {
                        hx = hz = 0.5f * static_cast<float>(rz.number(z, 1e-9, 1e30));
                    } else {
                        rz.fail("expected a positive number or [x, z], got " + json_excerpt(z));
                    }
                }
                glm::mat4 m = read_transform(s, rs);
                glm::vec3 q[4] = {{-hx, 0, -hz}, {hx, 0, -hz}, {hx, 0, hz}, {-hx, 0, hz}};
                for (auto& v : q)
                    v = glm::vec3(m * glm::vec4(c + v, 1.0f));
                glm::vec3 a[3] = {q[0], q[2], q[1]}, b[3] = {q[0], q[3], q[2]};
                // Texture coordinates: u along +x, v along -z (the image upright seen from above
                // with -z up), [0, 1] over the quad.
                const glm::vec2 t[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
                glm::vec2 ta[3] = {t[0], t[2], t[1]}, tb[3] = {t[0], t[3], t[2]};
                if (glm::determinant(glm::mat3(m)) < 0.0f) { // mirrored: the same front face
                    std::swap(a[1], a[2]);
                    std::swap(b[1], b[2]);
                    std::swap(ta[1], ta[2]);
                    std::swap(tb[1], tb[2]);
                }
                int qm = mat < 0 ? default_material() : mat;
                if (!add_triangle(scene.triangles, a, nullptr, qm, ta) ||
                    !add_triangle(scene.triangles, b, nullptr, qm, tb))
                    rs.fail("the quad is degenerate, or not finite or beyond " +
                            scene_range_text() + " after its transform");
            } else {
                rs.at("type").fail("unknown shape type " + json_excerpt(s["type"]) +
                                   " (use mesh, sphere or quad)");
            }
        }
    }
    if (scene.triangles.size() == 0)
        warn(path + ": the scene has no geometry; rendering the environment alone");
    if (scene.triangles.size() > static_cast<size_t>(kMaxDeviceIndex / 3))
        r.at("shapes").fail(std::to_string(scene.triangles.size()) +
                            " triangles: more than the device can index (" +
                            std::to_string(kMaxDeviceIndex / 3) + ")");
    return scene;
}

} // namespace et
