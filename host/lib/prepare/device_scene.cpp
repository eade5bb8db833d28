#include "prepare/device_scene.h"

#include "util/error.h"

#include <cstring>

namespace et {

int parse_strategy(const std::string& s) {
    if (s == "light")
        return ETK_STRATEGY_LIGHT;
    if (s == "bsdf")
        return ETK_STRATEGY_BSDF;
    if (s == "mis")
        return ETK_STRATEGY_MIS;
    if (s == "uniform")
        return ETK_STRATEGY_UNIFORM;
    throw Error("unknown strategy '" + s + "' (use light, bsdf, mis or uniform)");
}

int parse_heuristic(const std::string& s) {
    if (s == "balance")
        return ETK_HEURISTIC_BALANCE;
    if (s == "power")
        return ETK_HEURISTIC_POWER;
    throw Error("unknown MIS heuristic '" + s + "' (use balance or power)");
}

int parse_sampler(const std::string& s) {
    if (s == "sobol")
        return ETK_SAMPLER_SOBOL;
    if (s == "random")
        return ETK_SAMPLER_RANDOM;
    throw Error("unknown sampler '" + s + "' (use sobol or random)");
}

SceneArrays build_scene_arrays(const Scene& scene) {
    SceneArrays a;
    a.env = &scene.env;
    a.bvh = build_bvh(scene.triangles);
    a.tris = flatten_triangles(scene.triangles, a.bvh.order);
    const size_t n = a.bvh.order.size();
    a.normals.resize(3 * n);
    a.tri_material.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const int t = a.bvh.order[i];
        for (int k = 0; k < 3; ++k) {
            const glm::vec3& v = scene.triangles.normals[3 * t + k];
            a.normals[3 * i + k] = etk::make_float4(v.x, v.y, v.z, 0.0f);
        }
        a.tri_material[i] = scene.triangles.material[t];
    }
    if (n == 0)
        a.normals.resize(3), a.tri_material.resize(1), a.tris.resize(3);
    for (const auto& m : scene.materials) {
        uint32_t type = static_cast<uint32_t>(m.type);
        float type_bits;
        std::memcpy(&type_bits, &type, 4);
        a.materials.push_back(etk::make_float4(m.albedo.x, m.albedo.y, m.albedo.z, type_bits));
        a.materials.push_back(
            etk::make_float4(m.specular.x, m.specular.y, m.specular.z, m.roughness));
    }
    if (a.materials.empty())
        a.materials.resize(2);
    // Secondary rays start this far (relative to the coordinates' magnitude) off the surface.
    a.ray_epsilon = 2e-4f;
    return a;
}

etk::EtkScene scene_view(const SceneArrays& a) {
    return etk::EtkScene{a.bvh.nodes.data(),     a.tris.data(),      a.normals.data(),
                         a.tri_material.data(),  a.materials.data(), a.env->dist.table.data(),
                         a.env->image.rgb.data()};
}

etk::EtkParams make_params(const Scene& scene, const SceneArrays& arrays) {
    etk::EtkParams p{};
    p.env = scene.env.desc();
    const Camera& c = scene.camera;
    glm::vec3 f = glm::normalize(c.target - c.eye);
    glm::vec3 r = glm::normalize(glm::cross(f, c.up));
    glm::vec3 u = glm::cross(r, f);
    const float th = std::tan(0.5f * glm::radians(c.fov_deg));
    const float aspect = static_cast<float>(scene.width) / scene.height;
    r *= th * aspect;
    u *= th;
    for (int k = 0; k < 3; ++k) {
        p.eye[k] = c.eye[k];
        p.forward[k] = f[k];
        p.right[k] = r[k];
        p.up[k] = u[k];
    }
    p.width = scene.width;
    p.height = scene.height;
    p.max_depth = scene.settings.max_depth;
    p.rr_depth = scene.settings.rr_depth;
    p.strategy = parse_strategy(scene.settings.strategy);
    p.heuristic = parse_heuristic(scene.settings.heuristic);
    p.sampler = parse_sampler(scene.settings.sampler);
    p.seed = scene.settings.seed;
    p.ray_epsilon = arrays.ray_epsilon;
    return p;
}

} // namespace et
