// A scene as the renderer consumes it: camera, film, environment, a triangle soup with per-corner
// shading normals and per-triangle materials, and the render settings. Loaded from JSON
// (scenes/README.md documents the format).
#pragma once
#include "load/environment_map.h"
#include "load/render_settings.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace et {

struct Material {
    std::string name;
    int type = 0; // ETK_MAT_*
    glm::vec3 albedo{0.8f}, specular{0.0f};
    float roughness = 0.3f;
    float ior = 1.5f; // dielectrics: index of refraction inside (the front face is outside)
};

struct Camera {
    glm::vec3 eye{0, 1, 4}, target{0, 0, 0}, up{0, 1, 0};
    float fov_deg = 40.0f; // vertical
};

struct TriangleSoup {
    std::vector<glm::vec3> positions; // 3 per triangle
    std::vector<glm::vec3> normals;   // 3 per triangle (geometric when the mesh has none)
    std::vector<int> material;        // 1 per triangle
    size_t size() const { return material.size(); }
};

struct Scene {
    std::string path;
    Camera camera;
    int width = 512, height = 512;
    EnvMap env;
    TriangleSoup triangles;
    std::vector<Material> materials;
    RenderSettings settings;
    std::string output;
};

// Throws et::Error naming the file and the problem (with line:column for malformed JSON); warns
// about unknown keys, dropped degenerate triangles and odd OBJ content.
Scene load_scene(const std::string& path);

// Appends an OBJ file (triangulated; materials from its MTL unless `override_material` >= 0).
void load_obj(const std::string& path, const glm::mat4& transform, int override_material,
              std::vector<Material>& materials, TriangleSoup& out);

// Appends the triangle (a, b, c) unless it is degenerate or not finite; returns whether it did.
bool add_triangle(TriangleSoup& soup, const glm::vec3 p[3], const glm::vec3 n[3], int material);

} // namespace et
