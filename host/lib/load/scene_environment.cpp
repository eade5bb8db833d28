#include "load/scene_environment.h"

#include "util/data_path.h"
#include "util/error.h"
#include "util/json_file.h"
#include "load/sky.h"

namespace et {
namespace {

template <typename T>
T get_or(const nlohmann::json& j, const char* key, T fallback, const std::string& where) {
    if (!j.contains(key))
        return fallback;
    try {
        return j.at(key).get<T>();
    } catch (const nlohmann::json::exception&) {
        throw Error(where + ": '" + key + "' has the wrong type (" + j.at(key).dump() + ")");
    }
}

} // namespace

EnvMap load_scene_environment(const nlohmann::json& env, const std::string& scene_dir,
                              const std::string& where, DistributionOptions options) {
    const std::string w = where + ": environment";
    if (!env.is_object())
        throw Error(w + " must be an object with \"map\" or \"sky\"");
    warn_unknown_keys(
        env, {"map", "sky", "intensity", "rotation", "distribution_resolution", "blur"}, w);
    if (env.contains("distribution_resolution")) {
        auto r = env["distribution_resolution"];
        if (!r.is_array() || r.size() != 2 || !r[0].is_number_integer() ||
            !r[1].is_number_integer())
            throw Error(w + ": distribution_resolution must be [width, height]");
        options.width = r[0].get<int>();
        options.height = r[1].get<int>();
    }
    options.blur_sigma = get_or<float>(env, "blur", options.blur_sigma, w);
    EnvMap map;
    if (env.contains("map")) {
        const std::string path =
            resolve_data_file(get_or<std::string>(env, "map", "", w), scene_dir);
        map = load_envmap(path, options);
    } else if (env.contains("sky")) {
        const auto& s = env["sky"];
        const std::string ws = w + ".sky";
        warn_unknown_keys(s,
                          {"resolution", "sun_elevation", "sun_azimuth", "sun_radius",
                           "sun_radiance", "sky_radiance"},
                          ws);
        SkyParams p;
        if (s.contains("resolution")) {
            auto r = s["resolution"];
            if (!r.is_array() || r.size() != 2 || !r[0].is_number_integer() ||
                !r[1].is_number_integer() || r[0].get<int>() < 2 || r[1].get<int>() < 1 ||
                r[0].get<int>() > 16384 || r[1].get<int>() > 8192)
                throw Error(ws + ": resolution must be [width, height] within [2..16384, 1..8192]");
            p.width = r[0].get<int>();
            p.height = r[1].get<int>();
        }
        p.sun_elevation_deg = get_or<float>(s, "sun_elevation", p.sun_elevation_deg, ws);
        p.sun_azimuth_deg = get_or<float>(s, "sun_azimuth", p.sun_azimuth_deg, ws);
        p.sun_angular_radius_deg = get_or<float>(s, "sun_radius", p.sun_angular_radius_deg, ws);
        p.sun_radiance = get_or<float>(s, "sun_radiance", p.sun_radiance, ws);
        p.sky_radiance = get_or<float>(s, "sky_radiance", p.sky_radiance, ws);
        map = make_envmap("procedural sky", make_sky(p), options);
    } else {
        throw Error(w + " needs \"map\" (a lat-long image) or \"sky\" (procedural sun and sky)");
    }
    map.scale = get_or<float>(env, "intensity", 1.0f, w);
    map.rotation_degrees = get_or<float>(env, "rotation", 0.0f, w);
    if (!(map.scale >= 0.0f) || !std::isfinite(map.scale))
        throw Error(w + ": intensity must be a finite number >= 0");
    if (!std::isfinite(map.rotation_degrees))
        throw Error(w + ": rotation must be a finite number of degrees");
    return map;
}

} // namespace et
