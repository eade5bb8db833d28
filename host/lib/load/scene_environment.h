// The "environment" block of a scene file: a map file or the procedural sky, its intensity and
// its rotation about the up axis and the lat-long convention the map was made for.
#pragma once
#include "load/environment_map.h"

#include <nlohmann/json.hpp>

#include <map>
#include <string>

namespace et {

// `where` names the scene file for messages; files resolve against scene_dir, then ENVTRACE_DATA;
// "arrays" names one of `maps` (a scene's in-memory inputs, scene.h).
EnvMap load_scene_environment(const nlohmann::json& env, const std::string& scene_dir,
                              const std::string& where, DistributionOptions options,
                              const std::map<std::string, RgbImage>* maps = nullptr);

// An edit of a loaded map's block: "intensity", "rotation" and "convention" over its current
// values. The texels and the distribution stay (neither depends on them); keys that would change
// them are refused.
void edit_scene_environment(EnvMap& map, const nlohmann::json& env, const std::string& where);

} // namespace et
