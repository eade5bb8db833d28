#include "prepare/light_set.h"

#include "util/error.h"
#include "util/json_file.h"
#include "util/output_batch.h"
#include "kernels/envmap.h"
#include "kernels/sampler.h"
#include "util/timer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace et {
namespace {

glm::vec3 to_world(const EnvMap& env, const glm::dvec3& d) {
    const etk::float3 w =
        etk::etk_env_to_world(env.desc(), etk::make_float3(float(d.x), float(d.y), float(d.z)));
    return glm::normalize(glm::vec3(w.x, w.y, w.z));
}

} // namespace

LightSet make_lights_ours(const EnvMap& env, int n, uint32_t seed, bool voronoi_power) {
    if (n < 1)
        throw Error("need at least one light");
    if (!env.dist.has_light())
        throw Error(env.name + ": the map emits no light: no lights to make");
    LightSet set;
    set.method = "ours";
    set.power_rule = voronoi_power ? "voronoi" : "share";
    set.map = env.name;
    set.precompute_seconds = env.build_seconds;
    Timer timer;
    const etk::EtkEnvMap desc = env.desc();
    const float* dist = env.dist.table.data();
    const float* texels = env.image.rgb.data();
    std::vector<glm::dvec3> map_dirs;
    glm::dvec3 sum(0.0);
    for (int k = 0; k < n; ++k) {
        const etk::float2 u =
            etk::etk_sample_pair(ETK_SAMPLER_SOBOL, seed, 0u, static_cast<uint32_t>(k), 0u);
        const etk::EtkEnvSample s = etk::etk_env_sample(dist, desc, u);
        DirectionalLight l;
        l.direction = glm::normalize(glm::vec3(s.dir.x, s.dir.y, s.dir.z));
        if (s.pdf > 0.0f) {
            const etk::float3 L = etk::etk_env_radiance_uv(texels, desc, s.uv);
            l.power = glm::dvec3(L.x, L.y, L.z) / (double(n) * s.pdf);
        }
        sum += l.power;
        const etk::float3 m = etk::etk_world_to_env(desc, s.dir);
        map_dirs.push_back(glm::normalize(glm::dvec3(m.x, m.y, m.z)));
        set.lights.push_back(l);
    }
    set.map_power = map_power(env);
    if (voronoi_power) {
        VoronoiStrata v = voronoi_strata(env, map_dirs);
        for (int k = 0; k < n; ++k) {
            set.lights[k].power = v.power[k];
            // Texel solid angles summed in double can pass 4 pi by a rounding hair (one light
            // whose cell is the whole sphere): the file says 4 pi, which its reader accepts.
            set.lights[k].solid_angle = std::min(v.solid_angle[k], 4.0 * M_PI);
        }
    } else {
        for (int c = 0; c < 3; ++c) {
            const double f = sum[c] > 0.0 ? set.map_power[c] / sum[c] : 0.0;
            for (auto& l : set.lights)
                l.power[c] *= f;
        }
    }
    set.selection_seconds = timer.seconds();
    return set;
}

LightSet make_lights_sis(const EnvMap& env, int n, const SisOptions& options) {
    if (!env.dist.has_light()) // as make_lights_ours: no zero-power lights written as a result
        throw Error(env.name + ": the map emits no light: no lights to make");
    SisOptions o = options;
    o.samples = n;
    SisResult r = build_sis(env, o);
    LightSet set;
    set.method = "sis";
    set.power_rule = "voronoi";
    set.map = env.name;
    set.precompute_seconds = r.seconds;
    set.map_power = map_power(env);
    for (size_t k = 0; k < r.strata.points.size(); ++k) {
        DirectionalLight l;
        l.direction = to_world(env, r.strata.points[k]);
        l.power = r.strata.power[k];
        l.solid_angle = r.strata.solid_angle[k];
        set.lights.push_back(l);
    }
    return set;
}

void write_lights(const std::string& path, const LightSet& set) {
    OutputBatch batch({path});
    write_lights(batch, path, set);
    batch.commit();
}

void write_lights(OutputBatch& batch, const std::string& path, const LightSet& set) {
    using nlohmann::json;
    json lights = json::array();
    for (const auto& l : set.lights) {
        json j{{"direction", {l.direction.x, l.direction.y, l.direction.z}},
               {"power", {l.power.x, l.power.y, l.power.z}}};
        if (l.solid_angle > 0.0)
            j["solid_angle"] = l.solid_angle;
        lights.push_back(j);
    }
    json j{{"method", set.method},
           {"power_rule", set.power_rule},
           {"map", set.map},
           {"count", set.lights.size()},
           {"map_power", {set.map_power.x, set.map_power.y, set.map_power.z}},
           {"precompute_seconds", set.precompute_seconds},
           {"selection_seconds", set.selection_seconds},
           {"total_seconds", set.total_seconds()},
           {"lights", lights}};
    write_json_file(batch, path, j, 1);
}

LightSet read_lights(const std::string& path) {
    const nlohmann::json j = read_json_file(path, "light set");
    const JsonReader r(path);
    LightSet set;
    if (!j.is_object() || !j.contains("lights") || !j["lights"].is_array())
        r.fail("not a light set (expected an object with a 'lights' array)");
    // The keys write_lights writes: a hand-edited set's misspelt key is an error, not ignored.
    r.reject_unknown_keys(j,
                          {"method", "power_rule", "map", "count", "map_power",
                           "precompute_seconds", "selection_seconds", "total_seconds", "lights"});
    // Powers as the brightest map could give (4 pi x kMaxRadiance), so renders stay finite.
    const double max_value = 4.0 * M_PI * kMaxRadiance;
    auto vec = [&](const nlohmann::json& v, const JsonReader& rv, double lo) {
        if (!v.is_array() || v.size() != 3)
            rv.fail("expected an array of three numbers, got " + json_excerpt(v));
        glm::dvec3 out;
        for (int k = 0; k < 3; ++k)
            out[k] = rv.at(k).number(v[k], lo, max_value);
        return out;
    };
    set.method = r.string(j, "method", "");
    set.power_rule = r.string(j, "power_rule", "");
    set.map = r.string(j, "map", "");
    const JsonReader rl = r.at("lights");
    size_t i = 0;
    for (const auto& l : j["lights"]) {
        const JsonReader ri = rl.at(i);
        ri.expect_object(l);
        ri.reject_unknown_keys(l, {"direction", "power", "solid_angle"});
        if (!l.contains("direction") || !l.contains("power"))
            ri.fail("needs 'direction' and 'power'");
        DirectionalLight d;
        const glm::dvec3 dir = vec(l["direction"], ri.at("direction"), -max_value);
        const double len = glm::length(dir);
        if (!(len > 0.0) || !std::isfinite(len))
            ri.at("direction").fail("zero or non-finite direction");
        d.direction = glm::vec3(dir / len);
        d.power = vec(l["power"], ri.at("power"), 0.0);
        d.solid_angle = ri.number(l, "solid_angle", 0.0, 0.0, 4.0 * M_PI);
        set.lights.push_back(d);
        ++i;
    }
    if (set.lights.empty())
        r.fail("the light set is empty");
    // Together too: a render adds them all, and a sum past what the film holds would come out as
    // black pixels (non-finite samples are written as 0), not as an error.
    glm::dvec3 total(0.0);
    for (const DirectionalLight& d : set.lights)
        total += d.power;
    if (glm::any(glm::greaterThan(total, glm::dvec3(max_value)))) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "the lights' total power (%.4g, %.4g, %.4g) exceeds %.4g, the most a map "
                      "can hold (4 pi x the largest radiance)",
                      total.x, total.y, total.z, max_value);
        rl.fail(buf);
    }
    if (j.contains("count")) { // written by `envtrace lights`: a file cut short or edited?
        const JsonReader rc = r.at("count");
        const double count = rc.number(j["count"], 0.0, 1e12);
        if (count != static_cast<double>(set.lights.size()))
            rc.fail("says " + json_excerpt(j["count"]) + " lights, but 'lights' holds " +
                    std::to_string(set.lights.size()));
    }
    return set;
}

} // namespace et
