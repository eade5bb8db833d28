// Host precompute -> flat arrays: everything the integrator stages read, in the layouts of
// kernels/integrator.h, ready to upload or to hand to the native back end.
#pragma once
#include "prepare/bvh_build.h"
#include "kernels/integrator.h"
#include "load/scene.h"

#include <string>
#include <vector>

namespace et {

struct SceneArrays {
    Bvh bvh;
    std::vector<etk::float4> tris, normals, materials;
    std::vector<int> tri_material;
    const EnvMap* env = nullptr;
    float ray_epsilon = 1e-4f;
};

SceneArrays build_scene_arrays(const Scene& scene);

// The arrays as the integrator stages take them on the host (the native back end).
etk::EtkScene scene_view(const SceneArrays& arrays);

int parse_strategy(const std::string& s);
int parse_heuristic(const std::string& s);
int parse_sampler(const std::string& s);

// Per-pass parameters (the sample index and first pixel are set per pass).
etk::EtkParams make_params(const Scene& scene, const SceneArrays& arrays);

} // namespace et
