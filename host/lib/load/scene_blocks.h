// The blocks of a scene file that a loaded scene's edits (scene_edit.h) read again: the same
// readers, so that an edit is checked and parsed as the file is. `r` names where the block is.
#pragma once
#include "load/scene.h"
#include "util/json_file.h"

#include <nlohmann/json.hpp>

#include <string>

namespace et {

// The "camera" block over `camera` (keys absent keep its values).
Camera read_camera(const nlohmann::json& c, const JsonReader& r, Camera camera);
// The "render" block over `st`.
void read_render_block(const nlohmann::json& s, const JsonReader& r, RenderSettings& st);
// One material of the "materials" block; texture files resolve against `dir`.
Material read_material(const std::string& name, const nlohmann::json& j, const JsonReader& r,
                       const std::string& dir, TextureSet& textures);

} // namespace et
