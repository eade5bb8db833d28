// The scene's "mesh" shape: one loader per file format, chosen by the file's extension
// (docs/scene-format.md lists them).
#include "load/scene.h"
#include "util/error.h"
#include "util/file_check.h"

#include <cctype>
#include <filesystem>

namespace et {

void load_mesh(const std::string& path, const glm::mat4& transform, int override_material,
               std::vector<Material>& materials, TriangleSoup& out, TextureSet* textures) {
    const std::string ext = lower_extension(path);
    const size_t before = out.size();
    if (ext == ".ply")
        load_ply(path, transform, override_material, materials, out);
    else if (ext == ".gltf" || ext == ".glb")
        load_gltf(path, transform, override_material, materials, out);
    else // .obj, and any other name as before
        load_obj(path, transform, override_material, materials, out, textures);
    // A mirroring transform (negative determinant) turns every triangle's winding around, and
    // the winding says which side is outside (a dielectric's): turned back here, so that a
    // mirrored solid is the same solid. glTF's loader does it with its node transforms.
    if (ext != ".gltf" && ext != ".glb" && glm::determinant(glm::mat3(transform)) < 0.0f)
        reverse_winding(out, before);
    // A mesh that adds nothing is a mistake (another file, a point cloud, every face broken),
    // never a scene's intent: said, rather than rendering as if the mesh were there.
    if (out.size() == before)
        throw Error(path + ": no triangles to render (the file holds no faces, or every face "
                           "was skipped)");
}

} // namespace et
