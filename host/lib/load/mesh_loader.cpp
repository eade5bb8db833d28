// The scene's "mesh" shape: one loader per file format, chosen by the file's extension
// (scenes/README.md lists them).
#include "load/scene.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace et {

void load_mesh(const std::string& path, const glm::mat4& transform, int override_material,
               std::vector<Material>& materials, TriangleSoup& out, TextureSet* textures) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".ply")
        load_ply(path, transform, override_material, materials, out);
    else if (ext == ".gltf" || ext == ".glb")
        load_gltf(path, transform, override_material, materials, out);
    else // .obj, and any other name as before
        load_obj(path, transform, override_material, materials, out, textures);
}

} // namespace et
