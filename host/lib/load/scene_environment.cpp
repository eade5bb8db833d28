#include "load/scene_environment.h"

#include "util/data_path.h"
#include "util/error.h"
#include "util/json_file.h"
#include "load/sky.h"

#include <cmath>

namespace et {

namespace {

// Where the map stands: its intensity, rotation and convention ("intensity", "rotation",
// "convention"), over `p` for keys absent.
struct EnvPlacement {
    float scale = 1.0f, rotation = 0.0f;
    LatLongConvention convention = LatLongConvention::envtrace;
};

EnvPlacement read_placement(const nlohmann::json& env, const JsonReader& r, EnvPlacement p) {
    p.scale = static_cast<float>(r.number(env, "intensity", p.scale, 0.0, 1e30));
    p.rotation = static_cast<float>(r.number(env, "rotation", p.rotation, -1e6, 1e6));
    if (env.contains("convention")) {
        const JsonReader rc = r.at("convention");
        if (!parse_convention(rc.string(env["convention"]), p.convention))
            rc.fail("expected \"envtrace\", \"mitsuba\" or \"blender\", got " +
                    json_excerpt(env["convention"]));
    }
    return p;
}

void place(EnvMap& map, const EnvPlacement& p, const JsonReader& r) {
    map.scale = p.scale;
    map.rotation_degrees = p.rotation;
    map.convention = p.convention;
    bound_intensity(map, r.at("intensity").where());
}

} // namespace

void edit_scene_environment(EnvMap& map, const nlohmann::json& env, const std::string& where) {
    const JsonReader r = JsonReader(where).at("environment");
    if (!env.is_object())
        r.fail("expected an object, got " + json_excerpt(env));
    for (const char* key :
         {"map", "arrays", "sky", "distribution_resolution", "blur", "distribution_exponent"})
        if (env.contains(key))
            r.at(key).fail("changes the map or its distribution: load the scene again with it "
                           "(an edit changes \"intensity\", \"rotation\" and \"convention\")");
    r.reject_unknown_keys(env, {"intensity", "rotation", "convention"});
    place(map, read_placement(env, r, {map.scale, map.rotation_degrees, map.convention}), r);
}

EnvMap load_scene_environment(const nlohmann::json& env, const std::string& scene_dir,
                              const std::string& where, DistributionOptions options,
                              const std::map<std::string, RgbImage>* maps) {
    const JsonReader r = JsonReader(where).at("environment");
    if (!env.is_object())
        r.fail("expected an object with \"map\" or \"sky\", got " + json_excerpt(env));
    r.reject_unknown_keys(env, {"map", "arrays", "sky", "intensity", "rotation", "convention",
                                "distribution_resolution", "blur", "distribution_exponent"});
    if (env.contains("distribution_resolution")) {
        const auto& res = env["distribution_resolution"];
        const JsonReader rd = r.at("distribution_resolution");
        if (!res.is_array() || res.size() != 2)
            rd.fail("expected [width, height], got " + json_excerpt(res));
        options.width = static_cast<int>(rd.at(0).integer(res[0], 1, kMaxDistributionSide));
        options.height = static_cast<int>(rd.at(1).integer(res[1], 1, kMaxDistributionSide));
        // The table's size against what the device indexes and the memory budget, before
        // the map is read.
        try {
            check_distribution_size(options.width, options.height);
        } catch (const Error& e) {
            rd.fail(e.what());
        }
    }
    options.blur_sigma =
        static_cast<float>(r.number(env, "blur", options.blur_sigma, 0.0, kMaxBlurSigma));
    options.exponent = static_cast<float>(
        r.number(env, "distribution_exponent", options.exponent, kMinDistributionExponent, 1.0));
    const EnvPlacement placement = read_placement(env, r, {});
    EnvMap map;
    if (int(env.contains("map")) + int(env.contains("sky")) + int(env.contains("arrays")) > 1)
        r.fail("has more than one of \"map\", \"arrays\" and \"sky\": give one");
    if (env.contains("arrays")) {
        const std::string name = r.string(env, "arrays", "");
        const auto it = maps ? maps->find(name) : std::map<std::string, RgbImage>::const_iterator{};
        if (!maps || it == maps->end())
            r.at("arrays").fail("names no map given in memory with the scene");
        map = make_envmap(name, it->second, options);
    } else if (env.contains("map")) {
        const std::string name = r.string(env, "map", "");
        if (name.empty())
            r.at("map").fail("the file name is empty");
        const std::string path = resolve_data_file(name, scene_dir);
        map = load_envmap(path, options);
    } else if (const nlohmann::json* sp = r.object(env, "sky")) {
        const auto& s = *sp;
        const JsonReader rs = r.at("sky");
        rs.reject_unknown_keys(s, {"resolution", "sun_elevation", "sun_azimuth", "sun_radius",
                                   "sun_radiance", "sky_radiance"});
        SkyParams p;
        if (s.contains("resolution")) {
            const auto& res = s["resolution"];
            const JsonReader rr = rs.at("resolution");
            if (!res.is_array() || res.size() != 2)
                rr.fail("expected [width, height], got " + json_excerpt(res));
            p.width = static_cast<int>(rr.at(0).integer(res[0], 2, 16384));
            p.height = static_cast<int>(rr.at(1).integer(res[1], 1, 8192));
        }
        p.sun_elevation_deg =
            static_cast<float>(rs.number(s, "sun_elevation", p.sun_elevation_deg, -90, 90));
        p.sun_azimuth_deg =
            static_cast<float>(rs.number(s, "sun_azimuth", p.sun_azimuth_deg, -1e6, 1e6));
        p.sun_angular_radius_deg =
            static_cast<float>(rs.number(s, "sun_radius", p.sun_angular_radius_deg, 0.0, 90));
        p.sun_radiance =
            static_cast<float>(rs.number(s, "sun_radiance", p.sun_radiance, 0, kMaxRadiance));
        p.sky_radiance =
            static_cast<float>(rs.number(s, "sky_radiance", p.sky_radiance, 0, kMaxRadiance));
        map = make_envmap("procedural sky", make_sky(p), options);
    } else {
        r.fail("needs \"map\" (a lat-long image) or \"sky\" (procedural sun and sky)");
    }
    place(map, placement, r);
    return map;
}

} // namespace et
