// An environment map turned into N directional lights (paper, Section 4 and Figure 8), by our
// sampling or by SIS, and their JSON file (`envtrace lights`, `envtrace render --lights`).
//
// "ours": the first N points of the scrambled (0,2)-sequence (stream 0, pair 0, seed `seed`) are
// warped through the map's distribution (etk_env_sample) into directions w_k with densities
// p(w_k). Each light gets its unbiased share of the map's power, L(w_k) / (N p(w_k)) -- the
// light-sampling estimator with these N directions shared by every pixel -- and the N shares are
// then rescaled per channel so that they add up to the map's power exactly (their sum is only an
// estimate of it). With --power voronoi each light instead gets the exact power of its spherical
// Voronoi cell (sis.h), the same rule SIS uses.
// "sis": the SIS points (sis.h), each with its Voronoi cell's power.
#pragma once
#include "load/environment_map.h"
#include "prepare/sis.h"

#include <glm/glm.hpp>

#include <string>
#include <vector>

namespace et {

struct DirectionalLight {
    glm::vec3 direction{0.0f, 1.0f, 0.0f}; // world space, unit: where the light comes from
    glm::dvec3 power{0.0};                 // integral of L over the directions it stands for (RGB)
    double solid_angle = 0.0;              // of its Voronoi cell; 0 when not computed
};

struct LightSet {
    std::string method;     // ours | sis
    std::string power_rule; // share | voronoi
    std::string map;
    std::vector<DirectionalLight> lights;
    glm::dvec3 map_power{0.0};
    double precompute_seconds = 0.0; // distribution build (ours) or SIS levels+placement+strata
    double selection_seconds = 0.0;  // drawing the N directions and assigning their power (ours)
    double total_seconds() const { return precompute_seconds + selection_seconds; }
};

// `env` must be loaded with its distribution (load_envmap); its build time counts as precompute.
LightSet make_lights_ours(const EnvMap& env, int n, uint32_t seed, bool voronoi_power);
LightSet make_lights_sis(const EnvMap& env, int n, const SisOptions& options);

void write_lights(const std::string& path, const LightSet& set);
// The same as one file of a batch (util/output_batch.h), in place at batch.commit().
class OutputBatch;
void write_lights(OutputBatch& batch, const std::string& path, const LightSet& set);
// Throws et::Error naming the file on anything malformed.
LightSet read_lights(const std::string& path);

} // namespace et
