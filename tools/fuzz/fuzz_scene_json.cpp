// libFuzzer harness: a scene file through et::load_scene (JSON, camera, film, render settings,
// environment, materials, shapes and the meshes and maps they name). The scene is written beside
// small stand-ins made at start-up: map.hdr, map.exr (a 16x8 lat-long map) and mesh.obj with
// mesh.mtl; the seed corpus (tools/fuzz/make_corpus.py) points the example scenes at them.
#include "fuzz_common.h"
#include "image/image_io.h"
#include "load/scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace {

using json = nlohmann::json;
// Scenes that are valid but cost too much to load thousands of times a second are scaled down
// (the loaders bound these themselves, at sizes a real scene may use): a sky of up to 16384x8192
// texels (1024x512 by default), a distribution of up to 65536x65536 cells, spheres of up to 4096
// segments. This is not
// a mask: every key still reaches the loader, only with a smaller value. Returns whether it
// changed anything.
bool cap(json& j, const char* key, double most) {
    if (!j.is_object() || !j.contains(key) || !j[key].is_number())
        return false;
    if (!(j[key].get<double>() > most))
        return false;
    j[key] = most;
    return true;
}
bool cap_pair(json& j, const char* key, int w, int h) {
    if (!j.is_object() || !j.contains(key))
        return false;
    json& a = j[key];
    if (!a.is_array() || a.size() != 2 || !a[0].is_number() || !a[1].is_number())
        return false;
    bool changed = false;
    for (int i = 0; i < 2; ++i) // 64.0 is the integer 64 to the loaders: floats are capped too
        if (a[i].get<double>() > (i ? h : w)) {
            a[i] = i ? h : w;
            changed = true;
        }
    return changed;
}
bool scale_down(json& scene) {
    if (!scene.is_object())
        return false;
    bool changed = false;
    if (scene.contains("environment") && scene["environment"].is_object()) {
        json& env = scene["environment"];
        changed |= cap_pair(env, "distribution_resolution", 64, 32);
        if (env.contains("sky") && env["sky"].is_object()) {
            json& sky = env["sky"];
            if (!sky.contains("resolution")) { // the default, 1024x512, costs 0.1 s
                sky["resolution"] = {32, 16};
                changed = true;
            }
            changed |= cap_pair(sky, "resolution", 32, 16);
        }
    }
    if (scene.contains("shapes") && scene["shapes"].is_array())
        for (json& s : scene["shapes"])
            changed |= cap(s, "segments", 16.0);
    return changed;
}

void write_text(const std::string& name, const std::string& text) {
    std::ofstream(etfuzz::work_dir() + "/" + name) << text;
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    etfuzz::silence_warnings();
    std::vector<float> px(16 * 8 * 3);
    for (size_t i = 0; i < px.size(); ++i)
        px[i] = 0.05f + 0.1f * static_cast<float>(i % 7);
    px[3 * (2 * 16 + 5)] = 50.0f; // a bright spot
    et::write_image(etfuzz::work_dir() + "/map.hdr", 16, 8, 3, px);
    et::write_image(etfuzz::work_dir() + "/map.exr", 16, 8, 3, px);
    write_text("mesh.mtl", "newmtl red\nKd 0.8 0.1 0.1\nKs 0.04 0.04 0.04\nNs 100\n");
    write_text("mesh.obj", "mtllib mesh.mtl\n"
                           "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv 0 1 0\n"
                           "vn 0 1 0\n"
                           "usemtl red\n"
                           "f 1//1 2//1 5//1\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 3 2\n");
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const etfuzz::FdCheck fds;
    std::string text(reinterpret_cast<const char*>(data), size);
    json parsed = json::parse(text, nullptr, false);
    if (!parsed.is_discarded() && scale_down(parsed))
        text = parsed.dump();
    const std::string path = etfuzz::write_file(
        "scene.json", reinterpret_cast<const uint8_t*>(text.data()), text.size());
    try {
        et::Scene scene = et::load_scene(path);
        // What the renderer relies on.
        const size_t n = scene.triangles.size();
        if (scene.triangles.positions.size() != 3 * n || scene.triangles.normals.size() != 3 * n)
            std::abort();
        for (int m : scene.triangles.material)
            if (m < 0 || static_cast<size_t>(m) >= scene.materials.size())
                std::abort();
        if (scene.width < 1 || scene.height < 1 || !std::isfinite(scene.env.scale))
            std::abort();
    } catch (const et::Error&) {
    }
    return 0;
}
