// The "mesh" shape given as arrays: checked, then appended as the PLY loader appends a file's
// triangles, so that the same data gives the same triangles from either.
#include "load/mesh_arrays.h"
#include "load/scene.h"
#include "util/error.h"

#include <cmath>

namespace et {
namespace {

void check_arrays(const MeshArrays& m, const std::string& where) {
    const size_t n = m.positions.size();
    if (m.indices.size() % 3 != 0)
        throw Error(where + ": " + std::to_string(m.indices.size()) +
                    " indices: expected 3 per triangle");
    if (!m.normals.empty() && m.normals.size() != n)
        throw Error(where + ": " + std::to_string(m.normals.size()) + " normals for " +
                    std::to_string(n) + " vertices: expected one per vertex");
    if (!m.uvs.empty() && m.uvs.size() != n)
        throw Error(where + ": " + std::to_string(m.uvs.size()) + " uvs for " + std::to_string(n) +
                    " vertices: expected one per vertex");
    for (size_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(m.positions[v][k]))
                throw Error(where + ": vertex " + std::to_string(v) +
                            ": a coordinate is not a finite float");
    for (size_t i = 0; i < m.indices.size(); ++i)
        if (m.indices[i] >= n)
            throw Error(where + ": triangle " + std::to_string(i / 3) + ": vertex index " +
                        std::to_string(m.indices[i]) + " is out of range (" + std::to_string(n) +
                        " vertices)");
}

} // namespace

void append_mesh_arrays(const MeshArrays& m, const std::string& where, const glm::mat4& transform,
                        int override_material, std::vector<Material>& materials,
                        TriangleSoup& out) {
    check_arrays(m, where);
    int mat = override_material;
    if (mat < 0) {
        mat = static_cast<int>(materials.size());
        Material grey;
        grey.name = where + ":default";
        materials.push_back(grey);
    }
    const glm::mat3 normal_m = glm::transpose(glm::inverse(glm::mat3(transform)));
    const bool has_normals = !m.normals.empty(), has_uvs = !m.uvs.empty();
    const size_t before = out.size();
    size_t dropped = 0;
    for (size_t t = 0; t < m.indices.size() / 3; ++t) {
        glm::vec3 pp[3], nn[3];
        glm::vec2 tt[3];
        for (int q = 0; q < 3; ++q) {
            const uint32_t c = m.indices[3 * t + q];
            pp[q] = glm::vec3(transform * glm::vec4(m.positions[c], 1.0f));
            if (has_normals)
                nn[q] = normal_m * m.normals[c];
            if (has_uvs)
                tt[q] = m.uvs[c];
        }
        if (!add_triangle(out, pp, has_normals ? nn : nullptr, mat, has_uvs ? tt : nullptr))
            ++dropped;
    }
    if (dropped)
        warn(where + ": " + std::to_string(dropped) + " of " +
             std::to_string(m.indices.size() / 3) +
             " triangles skipped (degenerate, non-finite or out of range)");
    // As load_mesh does for a file: a mirroring transform's winding turned back, and a mesh
    // that adds nothing refused.
    if (glm::determinant(glm::mat3(transform)) < 0.0f)
        reverse_winding(out, before);
    if (out.size() == before)
        throw Error(where + ": no triangles to render (no indices, or every triangle was "
                            "skipped)");
}

} // namespace et
