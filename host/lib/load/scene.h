// A scene as the renderer consumes it: camera, film, environment, a triangle soup with per-corner
// shading normals and per-triangle materials, and the render settings. Loaded from JSON
// (docs/scene-format.md documents the format).
#pragma once
#include "load/environment_map.h"
#include "load/mesh_arrays.h"
#include "load/render_settings.h"
#include "load/texture.h"

#include <glm/glm.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace et {

struct Material {
    std::string name;
    int type = 0; // ETK_MAT_*
    glm::vec3 albedo{0.8f}, specular{0.0f};
    float roughness = 0.3f;
    // Textures (indices into Scene::textures, -1: none) that replace albedo, specular, roughness.
    int albedo_tex = -1, specular_tex = -1, roughness_tex = -1;
    float ior = 1.5f; // dielectrics: index of refraction inside (the front face is outside)
    // Conductors: complex index of refraction eta + i k per channel, relative to the outside;
    // the default is silver (Mitsuba 3.9.1's RGB eta and k for "Ag").
    glm::vec3 eta{0.155f, 0.117f, 0.138f}, k{4.83f, 3.12f, 2.15f};
};

struct Camera {
    glm::vec3 eye{0, 1, 4}, target{0, 0, 0}, up{0, 1, 0};
    float fov_deg = 40.0f; // vertical
};

struct TriangleSoup {
    std::vector<glm::vec3> positions; // 3 per triangle
    std::vector<glm::vec3> normals;   // 3 per triangle (geometric when the mesh has none)
    std::vector<int> material;        // 1 per triangle
    std::vector<glm::vec2> uvs;       // 3 per triangle: texture coordinates ((0, 0) when none)
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
    TextureSet textures;
};

// Throws et::Error naming the file and the problem (with line:column for malformed JSON); warns
// about unknown keys, dropped degenerate triangles and odd OBJ content.
Scene load_scene(const std::string& path);

// Inputs given in memory with a scene rather than as files (the Python module's arrays), by
// name: a "mesh" shape's "arrays" names a mesh, the environment's "arrays" a map.
struct SceneInputs {
    std::map<std::string, MeshArrays> meshes;
    std::map<std::string, RgbImage> maps; // linear RGB, lat-long
};

// The scene of a JSON document, as load_scene reads a file's: `path` names it in messages (and
// in the scene), files resolve against `dir`.
Scene load_scene_json(const nlohmann::json& j, const std::string& path, const std::string& dir,
                      const SceneInputs& inputs = {});

// Appends an OBJ file (triangulated, with its texture coordinates; materials from its MTL unless
// `override_material` >= 0). The MTL's map_Kd, map_Ks and map_Pr / map_Ns (roughness) are read
// into `textures`; without a TextureSet they are ignored.
void load_obj(const std::string& path, const glm::mat4& transform, int override_material,
              std::vector<Material>& materials, TriangleSoup& out, TextureSet* textures = nullptr);

// Appends a PLY file (ASCII or binary; polygons triangulated as fans; normals and u/v or s/t
// when present). Material: `override_material`, or a default grey one appended to `materials`.
void load_ply(const std::string& path, const glm::mat4& transform, int override_material,
              std::vector<Material>& materials, TriangleSoup& out);

// Appends the triangle primitives of a glTF 2.0 file's default scene (.gltf or .glb), with the
// node transforms applied before `transform`; its metallic-roughness materials become envtrace
// materials (docs/scene-format.md) unless `override_material` >= 0. Textures are not read (a
// warning).
void load_gltf(const std::string& path, const glm::mat4& transform, int override_material,
               std::vector<Material>& materials, TriangleSoup& out);

// Appends an in-memory mesh as load_ply appends a file's (the same transform of positions and
// normals, the same default material, the same triangles dropped, a mirroring transform's
// winding turned back); `where` names it in messages. Throws et::Error for an index out of
// range, per-vertex arrays of another length, a non-finite position or no triangle left.
void append_mesh_arrays(const MeshArrays& mesh, const std::string& where,
                        const glm::mat4& transform, int override_material,
                        std::vector<Material>& materials, TriangleSoup& out);

// Appends a mesh file by its extension: .ply, .gltf / .glb, else OBJ (load_obj).
void load_mesh(const std::string& path, const glm::mat4& transform, int override_material,
               std::vector<Material>& materials, TriangleSoup& out, TextureSet* textures = nullptr);

// The largest scene coordinate the kernels' float arithmetic holds: the triangle test multiplies
// three lengths (edges and the distance to a corner), which overflows a float beyond ~2e12 (and
// floats there are 1.2e5 apart). Triangles beyond it are dropped like degenerate ones; a camera
// or shape there is an error.
constexpr float kMaxSceneCoordinate = 1e12f;

// The unit normal of triangle p (counter-clockwise front), computed in double: a float cross
// product's squared length overflows for edges beyond ~4e9 and underflows below ~1e-19. Zero
// when the triangle is degenerate or not finite.
glm::vec3 unit_face_normal(const glm::vec3 p[3]);

// Appends the triangle (a, b, c) unless it is degenerate, not finite or beyond
// kMaxSceneCoordinate; returns whether it did. `uv`: its corners' texture coordinates, or nullptr
// for (0, 0).
bool add_triangle(TriangleSoup& soup, const glm::vec3 p[3], const glm::vec3 n[3], int material,
                  const glm::vec2 uv[3] = nullptr);

// Turns triangles from..end of the soup around (corners 1 and 2 swapped, with their normals and
// texture coordinates): the other side becomes the front.
void reverse_winding(TriangleSoup& soup, size_t from);

} // namespace et
