// Edits of a loaded scene, in the scene file's own schema: what changes without reading the
// scene's meshes or maps again (the Python module's Renderer edits).
#pragma once
#include "load/scene.h"

#include <nlohmann/json.hpp>

#include <string>

namespace et {

// Applies `edit`, an object of the scene file's blocks, to `scene`:
//   "camera", "render", "film": read over the scene's current values (keys absent stay);
//   "environment": "intensity", "rotation", "convention" over the map's (edit_scene_environment);
//   "materials": each named material's block replaces that material (texture files it names are
//                read, resolved against `dir`).
// Shapes and the map itself are not edited: a new scene is loaded for those. `where` names the
// edit in messages; throws et::Error as the loader would, leaving `scene` as it was.
void edit_scene(Scene& scene, const nlohmann::json& edit, const std::string& where,
                const std::string& dir);

} // namespace et
