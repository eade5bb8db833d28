#include "load/scene_edit.h"

#include "load/scene_blocks.h"
#include "load/scene_environment.h"
#include "util/error.h"
#include "util/json_file.h"

namespace et {
namespace {

using json = nlohmann::json;

int material_index(const Scene& s, const std::string& name, const JsonReader& r) {
    for (size_t i = 0; i < s.materials.size(); ++i)
        if (s.materials[i].name == name)
            return static_cast<int>(i);
    std::string known;
    for (const Material& m : s.materials)
        known += (known.empty() ? "" : ", ") + m.name;
    r.fail("the scene has no material of this name (it has: " + known + ")");
}

} // namespace

void edit_scene(Scene& scene, const json& edit, const std::string& where, const std::string& dir) {
    const JsonReader r(where);
    if (!edit.is_object())
        r.fail("an edit must be a JSON object, got " + json_excerpt(edit));
    r.reject_unknown_keys(edit, {"camera", "environment", "materials", "render", "film"});
    Scene s = scene; // all or nothing: the scene changes only once every block is read
    if (const json* c = r.object(edit, "camera"))
        s.camera = read_camera(*c, r.at("camera"), s.camera);
    if (const json* st = r.object(edit, "render"))
        read_render_block(*st, r.at("render"), s.settings);
    if (const json* f = r.object(edit, "film")) {
        const JsonReader rf = r.at("film");
        rf.reject_unknown_keys(*f, {"width", "height"});
        s.width = static_cast<int>(rf.integer(*f, "width", s.width, 1, 16384));
        s.height = static_cast<int>(rf.integer(*f, "height", s.height, 1, 16384));
    }
    if (edit.contains("environment"))
        edit_scene_environment(s.env, edit["environment"], where);
    if (const json* m = r.object(edit, "materials")) {
        const JsonReader rm = r.at("materials");
        for (auto it = m->begin(); it != m->end(); ++it) {
            const int i = material_index(s, it.key(), rm.at(it.key()));
            s.materials[static_cast<size_t>(i)] =
                read_material(it.key(), it.value(), rm.at(it.key()), dir, s.textures);
        }
    }
    scene = std::move(s);
}

} // namespace et
