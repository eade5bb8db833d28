// The "environment" block of a scene file: a map file or the procedural sky, its intensity and
// its rotation about the up axis and the lat-long convention the map was made for.
#pragma once
#include "load/environment_map.h"

#include <nlohmann/json.hpp>

namespace et {

// `where` names the scene file for messages; files resolve against scene_dir, then ENVTRACE_DATA.
EnvMap load_scene_environment(const nlohmann::json& env, const std::string& scene_dir,
                              const std::string& where, DistributionOptions options);

} // namespace et
