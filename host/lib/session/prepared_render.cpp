#include "session/prepared_render.h"

#include <utility>

namespace et {

std::unique_ptr<PreparedRender> prepare_render(Scene scene, const RenderSettings& st) {
    auto p = std::make_unique<PreparedRender>();
    if (st.strategy == Strategy::lights)
        p->light_set = read_lights(st.lights);
    if (st.strategy == Strategy::sis) {
        SisOptions so;
        so.samples = st.sis_samples;
        p->sis = build_sis(scene.env, so);
    }
    p->env_rotation_degrees = scene.env.rotation_degrees;
    p->env_intensity = scene.env.scale;
    p->env_convention = name_of(scene.env.convention);
    p->scene = prepare_device_scene(std::move(scene), st, &p->light_set.lights, &p->sis.strata);
    return p;
}

} // namespace et
