// A scene made ready to render: on the device's terms (DeviceScene), with the directional light
// set or the SIS strata its strategy draws from, and the environment settings the image's
// metadata records. Built once; a RenderSession renders it.
#pragma once
#include "load/render_settings.h"
#include "load/scene.h"
#include "prepare/device_scene.h"
#include "prepare/light_set.h"
#include "prepare/sis.h"

#include <memory>
#include <string>

namespace et {

struct PreparedRender {
    // The device scene points into light_set and sis: the three stay together, never moved
    // (prepare_render returns them behind a pointer).
    LightSet light_set; // --lights: read from settings.lights
    SisResult sis;      // strategy sis: the strata
    DeviceScene scene;
    // The scene's environment settings, as the metadata names them.
    double env_rotation_degrees = 0.0, env_intensity = 1.0;
    std::string env_convention;
};

// Reads the light set (strategy lights), precomputes the SIS strata (strategy sis) and builds
// the device scene for `settings`. Throws et::Error naming the file on bad input.
std::unique_ptr<PreparedRender> prepare_render(Scene scene, const RenderSettings& settings);

} // namespace et
