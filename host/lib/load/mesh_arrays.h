// An indexed triangle mesh held in memory (the Python module's arrays), appended to a scene as a
// mesh file's triangles are (append_mesh_arrays, scene.h).
#pragma once
#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace et {

struct MeshArrays {
    std::vector<glm::vec3> positions; // per vertex
    std::vector<uint32_t> indices;    // 3 per triangle, counter-clockwise front
    std::vector<glm::vec3> normals;   // per vertex, or none (geometric normals)
    std::vector<glm::vec2> uvs;       // per vertex, or none ((0, 0))
};

} // namespace et
