// The shared kernels under Valgrind's memcheck: tiny native renders of the shipped scenes with
// every strategy. The native back end runs the very stage functions of kernels/ that
// wavefront.cl runs, on path state the host allocates, so a stage that reads a field no earlier
// stage wrote, or branches on one, is reported here with its stack. ctest runs this program
// under `valgrind --error-exitcode=1` (tests/portability/CMakeLists.txt) and fails on any
// report; run alone it is an ordinary test.
//
// Why this exists beside Oclgrind: Oclgrind 21.10's uninitialised-value check reports the
// wavefront renders falsely (docs/portability.md, "Oclgrind"), so for wavefront.cl it checks
// bounds, races and the API only; this test covers uninitialised reads in those stages.
#include "load/scene.h"
#include "prepare/device_scene.h"
#include "render/executor_cpu.h"
#include "render/renderer.h"
#include "render_util.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace {

// Every material kind and texture input of the scene format, under a small procedural sky (a
// 1k map takes a minute to prepare under memcheck; the stages do not care about its size).
const char* kScene = R"({
  "camera": {"eye": [0, 1.2, 4.2], "target": [0, 0.6, 0], "up": [0, 1, 0], "fov": 50},
  "film": {"width": 8, "height": 6},
  "environment": {"sky": {"resolution": [64, 32], "sun_elevation": 35, "sun_azimuth": 40}},
  "materials": {
    "floor": {"type": "diffuse", "albedo": {"checker": {"color0": 0.6, "color1": 0.15}, "uv_scale": 6}},
    "clay": {"type": "diffuse", "albedo": [0.8, 0.35, 0.25]},
    "tiles": {"type": "plastic", "albedo": [0.1, 0.25, 0.7], "specular": [0.04, 0.04, 0.04],
              "roughness": {"checker": {"color0": 0.02, "color1": 0.5}}},
    "brushed": {"type": "microfacet", "roughness": 0.2, "specular": [0.95, 0.64, 0.54]},
    "chrome": {"type": "mirror", "specular": [0.9, 0.9, 0.9]},
    "gold": {"type": "conductor", "eta": [0.143, 0.375, 1.442], "k": [3.983, 2.386, 1.603], "roughness": 0.1},
    "glass": {"type": "dielectric", "ior": 1.5},
    "frosted": {"type": "dielectric", "ior": 1.5, "roughness": 0.15, "tint": [0.85, 0.95, 1.0]}
  },
  "shapes": [
    {"type": "quad", "center": [0, 0, 0], "size": 12, "material": "floor"},
    {"type": "sphere", "center": [-2.4, 0.5, 0], "radius": 0.5, "material": "clay", "segments": 12},
    {"type": "sphere", "center": [-1.2, 0.5, 0], "radius": 0.5, "material": "tiles", "segments": 12},
    {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "brushed", "segments": 12},
    {"type": "sphere", "center": [1.2, 0.5, 0], "radius": 0.5, "material": "chrome", "segments": 12},
    {"type": "sphere", "center": [2.4, 0.5, 0], "radius": 0.5, "material": "glass", "segments": 12},
    {"type": "sphere", "center": [0.6, 0.5, 1.2], "radius": 0.4, "material": "frosted", "segments": 12},
    {"type": "sphere", "center": [-0.6, 0.5, 1.2], "radius": 0.4, "material": "gold", "segments": 12}
  ],
  "render": {"spp": 2, "max_depth": 6, "strategy": "mis", "sampler": "sobol", "seed": 1}
})";

et::Scene load_small(const std::string& file) {
    et::Scene s = et::load_scene(file);
    s.width = 8;
    s.height = 6;
    return s;
}

std::string write_scene() {
    const std::string file = ::testing::TempDir() + "/memcheck_materials.json";
    std::ofstream(file) << kScene;
    return file;
}

// Two samples per pixel, so every stage runs with several paths in flight; samples 2 .. 16 too
// for the strategies that learn during samples 0 .. 15 and sample differently after.
void render_tiny(const et::DeviceScene& ds, bool past_learning) {
    auto r = et::make_renderer(ds);
    const uint32_t spp = past_learning ? 17 : 2;
    for (uint32_t k = 0; k < spp; ++k)
        r->render_sample(k);
    EXPECT_EQ(r->stats().nonfinite_samples, 0u);
    double sum = 0.0;
    for (float v : r->sums().mean())
        sum += v;
    EXPECT_GT(sum, 0.0);
}

void render_every_strategy(const et::Scene& s) {
    for (et::Strategy strategy :
         {et::Strategy::mis, et::Strategy::light, et::Strategy::bsdf, et::Strategy::uniform,
          et::Strategy::compensated, et::Strategy::visibility}) {
        SCOPED_TRACE(et::name_of(strategy));
        et::RenderSettings st = s.settings;
        st.strategy = strategy;
        st.backend = et::Backend::cpu;
        st.threads = 1;
        const bool learns = strategy == et::Strategy::visibility;
        render_tiny(et::prepare_device_scene(s, st), learns);
    }
}

TEST(Memcheck, EveryMaterialAndStrategyRendersNatively) {
    render_every_strategy(load_small(write_scene()));
}

TEST(Memcheck, MeshSceneRendersNatively) {
    ETT_DATA_FILE(mesh, "meshes/cornell_box.obj");
    render_every_strategy(
        load_small(std::string(ENVTRACE_SOURCE_DIR) + "/scenes/cornell_box.json"));
}

TEST(Memcheck, LightSetAndSisRenderNatively) {
    const et::Scene s = load_small(write_scene());
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::cpu;
    st.threads = 1;
    for (const auto& [strategy, ds] : ett::light_set_and_sis_scenes(s, st)) {
        SCOPED_TRACE(et::name_of(strategy));
        render_tiny(ds, false);
    }
}

// The control, run by ctest under memcheck_control.sh: the native lanes' path state must start
// unwritten, as a device's does, or memcheck could never see a stage read a field no stage
// wrote (a zeroed field is "initialised"). Reading the paths' depths before any stage ran and
// branching on them must be reported, with the lane's allocation as the origin.
TEST(MemcheckControl, UnwrittenPathStateIsReported) {
    const et::Scene s = load_small(write_scene());
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::cpu;
    const et::DeviceScene ds = et::prepare_device_scene(s, st);
    et::Film film(s.width, s.height);
    et::CpuDevice device(ds, film, 1, 16);
    std::vector<int> depths(16);
    device.lane(0).read_fields(16, {{etk::ETK_FIELD_depth, depths.data()}});
    int negative = 0;
    for (int d : depths)
        negative += d < 0 ? 1 : 0; // the branch memcheck must report
    std::printf("control: %d of 16 unwritten depths negative\n", negative);
}

} // namespace
