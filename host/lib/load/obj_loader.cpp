#include "util/error.h"
#include "kernels/bsdf.h"
#include "load/scene.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace et {

bool add_triangle(TriangleSoup& soup, const glm::vec3 p[3], const glm::vec3 n[3], int material) {
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(p[k].x) || !std::isfinite(p[k].y) || !std::isfinite(p[k].z))
            return false;
    glm::vec3 ng = glm::cross(p[1] - p[0], p[2] - p[0]);
    float area2 = glm::length(ng);
    if (!(area2 > 0.0f) || !std::isfinite(area2))
        return false;
    ng /= area2;
    for (int k = 0; k < 3; ++k) {
        soup.positions.push_back(p[k]);
        glm::vec3 nk = n ? n[k] : ng;
        float l = glm::length(nk);
        soup.normals.push_back(l > 0.0f && std::isfinite(l) ? nk / l : ng);
    }
    soup.material.push_back(material);
    return true;
}

void load_obj(const std::string& path, const glm::mat4& transform, int override_material,
              std::vector<Material>& materials, TriangleSoup& out) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw Error(path + ": is a directory, not an OBJ file");
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    config.mtl_search_path = std::filesystem::path(path).parent_path().string();
    tinyobj::ObjReader reader;
    if (!reader.ParseFromFile(path, config)) {
        std::string msg = reader.Error();
        while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' '))
            msg.pop_back();
        for (auto& c : msg)
            if (c == '\n')
                c = ';';
        throw Error(path + ": cannot read OBJ: " + (msg.empty() ? "unknown error" : msg));
    }
    if (!reader.Warning().empty()) {
        std::string w = reader.Warning();
        while (!w.empty() && w.back() == '\n')
            w.pop_back();
        for (auto& c : w)
            if (c == '\n')
                c = ';';
        warn(path + ": " + w);
    }
    const auto& attrib = reader.GetAttrib();
    const auto& shapes = reader.GetShapes();
    const auto& mtls = reader.GetMaterials();

    // OBJ/MTL materials map onto ours: Kd -> albedo, Ks/Ns -> specular/roughness.
    const int base = static_cast<int>(materials.size());
    if (override_material < 0) {
        for (const auto& m : mtls) {
            Material mat;
            mat.name = m.name;
            mat.albedo =
                glm::clamp(glm::vec3(m.diffuse[0], m.diffuse[1], m.diffuse[2]), 0.0f, 1.0f);
            mat.specular =
                glm::clamp(glm::vec3(m.specular[0], m.specular[1], m.specular[2]), 0.0f, 1.0f);
            float ns = std::isfinite(m.shininess) ? std::max(0.0f, m.shininess) : 0.0f;
            mat.roughness = std::clamp(std::sqrt(2.0f / (ns + 2.0f)), 0.01f, 1.0f);
            mat.type = std::max({mat.specular.x, mat.specular.y, mat.specular.z}) > 0.0f
                           ? ETK_MAT_MICROFACET
                           : ETK_MAT_DIFFUSE;
            materials.push_back(mat);
        }
    }
    int default_material = override_material;
    if (default_material < 0) {
        default_material = static_cast<int>(materials.size());
        Material grey;
        grey.name = path + ":default";
        materials.push_back(grey);
    }

    const glm::mat3 normal_m = glm::transpose(glm::inverse(glm::mat3(transform)));
    const size_t nv = attrib.vertices.size() / 3, nn = attrib.normals.size() / 3;
    size_t dropped = 0, bad_index = 0;
    for (const auto& shape : shapes) {
        size_t offset = 0;
        for (size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
            const int fv = shape.mesh.num_face_vertices[f];
            if (fv != 3) { // points or lines, or a polygon tinyobjloader could not triangulate
                offset += fv;
                ++dropped;
                continue;
            }
            glm::vec3 p[3], n[3];
            bool has_normals = true, ok = true;
            for (int k = 0; k < 3; ++k) {
                const auto& idx = shape.mesh.indices[offset + k];
                if (idx.vertex_index < 0 || static_cast<size_t>(idx.vertex_index) >= nv) {
                    ok = false;
                    break;
                }
                const float* v = &attrib.vertices[3 * idx.vertex_index];
                p[k] = glm::vec3(transform * glm::vec4(v[0], v[1], v[2], 1.0f));
                if (idx.normal_index >= 0 && static_cast<size_t>(idx.normal_index) < nn) {
                    const float* vn = &attrib.normals[3 * idx.normal_index];
                    n[k] = normal_m * glm::vec3(vn[0], vn[1], vn[2]);
                } else {
                    has_normals = false;
                }
            }
            offset += 3;
            if (!ok) {
                ++bad_index;
                continue;
            }
            int mat = default_material;
            if (override_material < 0 && f < shape.mesh.material_ids.size()) {
                int id = shape.mesh.material_ids[f];
                if (id >= 0 && id < static_cast<int>(mtls.size()))
                    mat = base + id;
            }
            if (!add_triangle(out, p, has_normals ? n : nullptr, mat))
                ++dropped;
        }
    }
    if (bad_index)
        warn(path + ": " + std::to_string(bad_index) +
             " faces with invalid vertex indices skipped");
    if (dropped)
        warn(path + ": " + std::to_string(dropped) +
             " degenerate, non-finite or non-triangle faces skipped");
}

} // namespace et
