// Preparation's product: everything the devices read, owned here, in the layouts of
// kernels/path_state.h (one vector per scene buffer, named as the buffer) plus the per-pass
// parameters. Both back ends render from it; the OpenCL one uploads the vectors as they are.
#pragma once
#include "kernels/integrator.h"
#include "load/scene.h"
#include "prepare/light_set.h"
#include "prepare/sis.h"
#include "prepare/visibility_tables.h"

#include <vector>

namespace et {

using etk::float4;

struct DeviceScene {
#define ET_SCENE_VECTOR(type, name) std::vector<type> name;
    ETK_SCENE_BUFFERS(ET_SCENE_VECTOR)
#undef ET_SCENE_VECTOR
    etk::EtkParams params{}; // camera, film, environment, settings; sample index set per pass
    RenderSettings settings;
    std::string scene_path, map_name;
    std::vector<std::string> material_names; // by material index
    size_t triangle_count = 0;
    int map_width = 0, map_height = 0;
    double map_build_seconds = 0.0;
    double guide_map_power = 0.0; // visibility strategy: the learning's unit
    // Visibility strategy: its grid (slots and resolution are fixed here, by the tables sized for
    // them) and how it learns (the rest may be changed before a renderer is made).
    VisibilityOptions guide_options;
    struct {
        int nodes = 0, depth = 0;
        double sah_cost = 0.0, build_seconds = 0.0;
    } bvh;

    // Words of the learned light sample's record sums on the device (kernels/visibility_record.h):
    // 0 unless the scene learns them.
    size_t guide_sum_words() const {
        return params.light_first == ETK_LIGHT_LEARNED
                   ? static_cast<size_t>(
                         etk::etk_gsum_words(params.guide_slots, params.guide_continuation))
                   : 0;
    }

    int width() const {
        return params.width;
    }
    int height() const {
        return params.height;
    }
    // The buffers as the stages take them on the host (the native back end).
    etk::EtkScene view() const;
};

// Builds the BVH and the flat arrays. The scene is taken by value: move it in when it is no
// longer needed, and the map's texels and distribution move rather than copy. Light sets and
// SIS strata (settings.strategy lights / sis) come from `lights` or `sis`.
DeviceScene prepare_device_scene(Scene scene, const RenderSettings& settings,
                                 const std::vector<DirectionalLight>* lights = nullptr,
                                 const VoronoiStrata* sis = nullptr);

} // namespace et
