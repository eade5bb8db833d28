// The OpenCL and native back ends run the same integrator stages (kernels/integrator.h) on the
// same sample values (regenerated bit-identically from pixel, index and dimension), so:
// - at max_depth 1, with the same scene, seed and sampler, the images are equal up to float
//   rounding: per-pixel relative difference below 1e-4 wherever the value is above 1e-3 of the
//   image mean. In fact they are bit-identical: FMA contraction is off on both sides
//   and the shared headers use their own trig and vector geometry, not built-ins;
// - at depth 5, where rounding differences grow into different paths (a continuation ray that
//   grazes an edge hits another triangle, Russian roulette compares against a value that moved
//   by an ulp), they agree statistically: the calibrated z statistics of render_util.h (mean
//   z^2 <= 1.3, |z| > 4 in at most 0.5% of values, image means within 5 sigma).
// Scenes: spheres on a ground quad under pisa, and bunny_5k on a quad under grace,
// royal_esplanade_1k and pedestrian_overpass_1k, written as scene files and loaded by
// load_scene.
#include "prepare/light_set.h"
#include "render/executor_cpu.h"
#include "render/renderer.h"
#include "prepare/sis.h"
#include "render_util.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

namespace {

std::string write_scene(const std::string& name, const std::string& map, bool bunny) {
    const std::string dir = ett::scratch_dir("backends-" + name);
    const std::string path = dir + "/scene.json";
    std::ofstream f(path);
    f << R"({
  "camera": {"eye": [0, 1.1, 3.4], "target": [0, 0.6, 0], "up": [0, 1, 0], "fov": 36},
  "film": {"width": 48, "height": 32},
  "environment": {"map": ")"
      << map << R"(", "rotation": 30},
  "materials": {
    "ground": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
    "glossy": {"type": "plastic", "albedo": [0.2, 0.3, 0.7], "roughness": 0.2},
    "metal": {"type": "microfacet", "specular": [0.9, 0.8, 0.6], "roughness": 0.35},
    "chrome": {"type": "mirror", "specular": [0.9, 0.9, 0.9]},
    "gold": {"type": "conductor", "eta": [0.143, 0.375, 1.442], "k": [3.983, 2.386, 1.603],
             "roughness": 0.25}
  },
  "shapes": [
    {"type": "quad", "center": [0, 0, 0], "size": 8, "material": "ground"},
)";
    if (bunny)
        f << R"(    {"type": "mesh", "file": ")" << ett::data_file("meshes/bunny_5k.obj")
          << R"(", "material": "glossy",
     "transform": {"translate": [0.17, -0.33, 0], "scale": 10}},
    {"type": "sphere", "center": [1.3, 0.4, -0.5], "radius": 0.4, "material": "chrome"}
)";
    else
        f << R"(    {"type": "sphere", "center": [-1.0, 0.5, 0], "radius": 0.5, "material": "gold"},
    {"type": "sphere", "center": [0, 0.5, -0.2], "radius": 0.5, "material": "metal"},
    {"type": "sphere", "center": [1.0, 0.5, 0], "radius": 0.5, "material": "chrome",
     "segments": 24, "smooth": false}
)";
    f << "  ]\n}\n";
    return path;
}

struct Case {
    const char* name;
    const char* map;
    bool bunny;
    double lit = 0.5; // the share of the film's values that must be lit enough to compare
};

// OpenCL's film against the native one: equal up to float rounding in every value above a floor.
void expect_equal_up_to_rounding(const Case& c, const et::Scene& s, const ett::RenderResult& cl,
                                 const ett::RenderResult& cpu) {
    const double floor = 1e-3 * ett::image_mean(cpu.mean);
    double worst = 0.0;
    int compared = 0, over = 0;
    for (size_t i = 0; i < cpu.mean.size(); ++i) {
        const double a = cl.mean[i], b = cpu.mean[i];
        ASSERT_TRUE(std::isfinite(a) && std::isfinite(b));
        if (std::max(a, b) <= floor)
            continue;
        ++compared;
        const double rel = std::fabs(a - b) / std::max(a, b);
        worst = std::max(worst, rel);
        over += rel >= 1e-4;
        if (rel >= 1e-4) {
            ADD_FAILURE() << c.name << ": pixel " << i / 3 << " (" << (i / 3) % s.width << ", "
                          << (i / 3) / s.width << ") channel " << i % 3 << ": opencl " << a
                          << ", cpu " << b << " (relative " << rel << ")";
        }
    }
    std::printf("%-22s depth 1: %d values compared, worst relative difference %.3g, %d >= 1e-4\n",
                c.name, compared, worst, over);
    EXPECT_GT(compared, static_cast<int>(c.lit * cpu.mean.size()));
    EXPECT_EQ(over, 0) << "values differing by 1e-4 relative or more";
}

// Every test's scene: the case's map (and the bunny) in a scene file, loaded; the test is skipped
// when the shared data lacks them.
class Backends : public ::testing::TestWithParam<Case> {
  protected:
    void SetUp() override {
        const Case c = GetParam();
        ETT_DATA_FILE(map, std::string("envmaps/") + c.map);
        if (c.bunny && ett::data_file("meshes/bunny_5k.obj").empty())
            GTEST_SKIP() << "meshes/bunny_5k.obj not found";
        scene_ = et::load_scene(write_scene(c.name, map, c.bunny));
    }
    et::Scene scene_;
};

TEST_P(Backends, DepthOneEqualUpToRounding) {
    const Case c = GetParam();
    et::Scene s = scene_;
    s.settings.max_depth = 1;
    s.settings.sampler = et::SamplerKind::sobol;
    s.settings.seed = 11;
    const int spp = 20;
    // The paper's MIS, and MIS with the compensated distribution and visible-normal sampling.
    // The visibility strategy: its tables learned from the first passes on each back end (equal
    // records, summed in fixed point, give equal tables).
    // The cosine strategy: its bins' tables, prepared once, the same for both.
    for (et::Strategy strategy : {et::Strategy::mis, et::Strategy::compensated,
                                  et::Strategy::visibility, et::Strategy::cosine}) {
        SCOPED_TRACE(et::name_of(strategy));
        s.settings.strategy = strategy;
        const auto cl = ett::render(s, "opencl", spp, false);
        const auto cpu = ett::render(s, "cpu", spp, false);
        expect_equal_up_to_rounding(c, s, cl, cpu);
    }
    // Splitting: the extra samples' rays are traced in the shade stage.
    s.settings.strategy = et::Strategy::mis;
    s.settings.light_samples = 4;
    s.settings.bsdf_samples = 2;
    SCOPED_TRACE("mis, 4 light and 2 BSDF samples per vertex");
    expect_equal_up_to_rounding(c, s, ett::render(s, "opencl", 4, false),
                                ett::render(s, "cpu", 4, false));
}

TEST_P(Backends, DepthFiveAgreeStatistically) {
    const Case c = GetParam();
    et::Scene s = scene_;
    s.settings.max_depth = 5;
    s.settings.sampler = et::SamplerKind::random;
    // The paper's MIS, and the visibility strategy, whose diffuse vertices also guide their
    // continuations at depth > 1 (kernels/continuation_guide.h): tables learned on each back end.
    for (et::Strategy strategy : {et::Strategy::mis, et::Strategy::visibility}) {
        SCOPED_TRACE(et::name_of(strategy));
        s.settings.strategy = strategy;
        const int spp = 128;
        s.settings.seed = 21;
        const auto cl = ett::render(s, "opencl", spp);
        s.settings.seed = 22; // independent noise: the statistics assume it
        const auto cpu = ett::render(s, "cpu", spp);
        const ett::Agreement g = ett::agreement(cl, cpu);
        std::printf("%-22s %-10s depth 5: means %.5f / %.5f (z %.2f), mean z^2 %.3f, max |z| "
                    "%.2f, |z|>4 %.4f\n",
                    c.name, et::name_of(strategy), g.mean_a, g.mean_b, g.mean_z, g.mean_z2,
                    g.max_abs_z, g.frac_over_4);
        EXPECT_LE(std::fabs(g.mean_z), 5.0);
        EXPECT_LE(g.mean_z2, 1.3);
        EXPECT_LE(g.frac_over_4, 0.005);
    }
}

// Directional light sets (the shade_lights stage) and SIS (one stratum per sample through the
// shadow queue) are stages of the same schedule: both back ends give bit-identical films.
TEST_P(Backends, LightSetAndSisFilmsBitIdentical) {
    const et::Scene& s = scene_;
    const et::LightSet set = et::make_lights_ours(s.env, 24, 1, false);
    et::SisOptions so;
    so.samples = 8;
    const et::SisResult sis = et::build_sis(s.env, so);
    for (et::Strategy strategy : {et::Strategy::lights, et::Strategy::sis}) {
        SCOPED_TRACE(et::name_of(strategy));
        et::FilmSums films[2];
        uint64_t shadow_rays[2] = {};
        for (et::Backend b : {et::Backend::opencl, et::Backend::cpu}) {
            et::RenderSettings st = s.settings;
            st.strategy = strategy;
            st.max_depth = 1;
            st.backend = b;
            st.threads = 2;
            const et::DeviceScene ds = et::prepare_device_scene(s, st, &set.lights, &sis.strata);
            auto r = et::make_renderer(ds);
            for (uint32_t k = 0; k < 8; ++k)
                r->render_sample(k);
            films[static_cast<int>(b)] = r->sums();
            shadow_rays[static_cast<int>(b)] = r->stats().shadow_rays;
            EXPECT_EQ(r->stats().nonfinite_samples, 0u);
        }
        EXPECT_GT(shadow_rays[0], 0u);
        EXPECT_EQ(shadow_rays[0], shadow_rays[1]);
        const std::vector<float> a = films[0].mean(), b = films[1].mean();
        double sum = 0.0;
        for (float v : b)
            sum += v;
        EXPECT_GT(sum, 0.0);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)))
            << "the back ends' images differ";
    }
}

// The sample_lights stage draws the light samples of the light, mis, compensated and cosine
// strategies in batches ahead of the shade stage (kernels/integrator.h; the cosine strategy's
// first vertex from its bins' tables; the visibility strategy's learned ones:
// VisibilityRender.BatchedLearnedLightSamplesGiveTheSameBits); without it the shade stage draws
// each itself. The same values: bit-identical films on each back end, at depth 3 (shade queues of
// many lengths, their last batch partly past the queue's end, vertices of three depths).
TEST_P(Backends, BatchedLightSamplesGiveTheSameBits) {
    const et::Scene& s = scene_;
    const et::LightBatch modes[] = {et::LightBatch::off, et::LightBatch::on,
                                    et::LightBatch::automatic};
    for (et::Strategy strategy :
         {et::Strategy::mis, et::Strategy::compensated, et::Strategy::light, et::Strategy::cosine})
        for (et::Backend b : {et::Backend::opencl, et::Backend::cpu}) {
            SCOPED_TRACE(std::string(et::name_of(strategy)) +
                         (b == et::Backend::cpu ? ", native" : ", OpenCL"));
            std::vector<float> films[3];
            for (int m = 0; m < 3; ++m) {
                SCOPED_TRACE(std::string("--light-batch ") + et::name_of(modes[m]));
                et::RenderSettings st = s.settings;
                st.strategy = strategy;
                st.max_depth = 3;
                st.seed = 5;
                st.backend = b;
                st.threads = 2;
                st.light_batch = modes[m];
                const et::DeviceScene ds = et::prepare_device_scene(s, st);
                auto r = et::make_renderer(ds);
                for (uint32_t k = 0; k < 6; ++k)
                    r->render_sample(k);
                films[m] = r->sums().mean();
                double stage = 0.0; // the stage ran only when asked to
                for (const auto& [name, sec] : r->stats().stage_seconds)
                    stage += name == "sample_lights" ? sec : 0.0;
                EXPECT_EQ(stage > 0.0, r->batches_light_samples())
                    << "sample_lights time " << stage;
                if (modes[m] != et::LightBatch::automatic) {
                    EXPECT_EQ(r->batches_light_samples(), modes[m] == et::LightBatch::on);
                } else if (b == et::Backend::cpu) { // auto batches on a CPU
                    EXPECT_TRUE(r->batches_light_samples());
                }
            }
            double sum = 0.0;
            for (float v : films[0])
                sum += v;
            EXPECT_GT(sum, 0.0);
            for (int m = 1; m < 3; ++m) {
                ASSERT_EQ(films[0].size(), films[m].size());
                EXPECT_EQ(0, std::memcmp(films[0].data(), films[m].data(),
                                         films[0].size() * sizeof(float)))
                    << "--light-batch " << et::name_of(modes[m]) << " changed the image";
            }
        }
}

// The binned light samples' batch where its steps meet their edge cases: a rough glass sphere
// filling much of the view (its vertices take the full map: batches that mix both, and batches of
// glass alone) and a map of 8 rows, fewer than the bins' 16 region bands (regions without rows).
// The same bits batched and one at a time, on both back ends.
TEST(BackendsBinned, GlassAndAShortMapGiveTheSameBits) {
    const std::string path = ett::scratch_dir("backends-binned") + "/scene.json";
    std::ofstream(path) << R"({
  "camera": {"eye": [0, 1.0, 2.6], "target": [0, 0.5, 0], "up": [0, 1, 0], "fov": 40},
  "film": {"width": 40, "height": 30},
  "environment": {"sky": {"resolution": [32, 8], "sun_elevation": 40, "sun_azimuth": 30,
                          "sun_radius": 3, "sun_radiance": 400, "sky_radiance": 1}},
  "materials": {
    "ground": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
    "glass": {"type": "dielectric", "ior": 1.5, "roughness": 0.3},
    "gold": {"type": "conductor", "eta": [0.143, 0.375, 1.442], "k": [3.983, 2.386, 1.603],
             "roughness": 0.2}
  },
  "shapes": [
    {"type": "quad", "center": [0, 0, 0], "size": 8, "material": "ground"},
    {"type": "sphere", "center": [-0.1, 0.55, 0], "radius": 0.55, "material": "glass"},
    {"type": "sphere", "center": [0.9, 0.3, -0.4], "radius": 0.3, "material": "gold"}
  ]
}
)";
    const et::Scene s = et::load_scene(path);
    for (et::Backend b : {et::Backend::opencl, et::Backend::cpu}) {
        SCOPED_TRACE(b == et::Backend::cpu ? "native" : "OpenCL");
        std::vector<float> films[2];
        for (int m = 0; m < 2; ++m) {
            et::RenderSettings st = s.settings;
            st.strategy = et::Strategy::cosine;
            st.max_depth = 3;
            st.seed = 3;
            st.backend = b;
            st.threads = 2;
            st.light_batch = m ? et::LightBatch::on : et::LightBatch::off;
            const et::DeviceScene ds = et::prepare_device_scene(s, st); // the renderer reads it
            auto r = et::make_renderer(ds);
            for (uint32_t k = 0; k < 4; ++k)
                r->render_sample(k);
            EXPECT_EQ(r->batches_light_samples(), m == 1);
            films[m] = r->sums().mean();
        }
        double sum = 0.0;
        for (float v : films[0])
            sum += v;
        EXPECT_GT(sum, 0.0);
        ASSERT_EQ(films[0].size(), films[1].size());
        EXPECT_EQ(0, std::memcmp(films[0].data(), films[1].data(), films[0].size() * sizeof(float)))
            << "the batch changed the image";
    }
}

// --light-batch auto follows the device: a native device that, like a GPU, prefers one sample
// per work-item renders without the stage under auto and with it under on; the same bits.
class SingleSampleDevice : public et::CpuDevice {
  public:
    using et::CpuDevice::CpuDevice;
    bool prefers_light_batches() const override { return false; }
};

TEST(LightBatch, AutoFollowsTheDevice) {
    const et::Scene s = ett::ground_under_uneven_sky(16, 12);
    std::vector<float> films[3];
    const et::LightBatch modes[] = {et::LightBatch::automatic, et::LightBatch::on,
                                    et::LightBatch::off};
    for (int m = 0; m < 3; ++m) {
        et::RenderSettings st = s.settings;
        st.max_depth = 2;
        st.strategy = et::Strategy::compensated; // one whose light samples may come in batches
        st.light_batch = modes[m];
        const et::DeviceScene ds = et::prepare_device_scene(s, st);
        et::Renderer r(ds, [&](et::Film& film) -> std::unique_ptr<et::WavefrontDevice> {
            return std::make_unique<SingleSampleDevice>(ds, film, 2);
        });
        for (uint32_t k = 0; k < 4; ++k)
            r.render_sample(k);
        EXPECT_EQ(r.batches_light_samples(), modes[m] == et::LightBatch::on)
            << et::name_of(modes[m]);
        films[m] = r.sums().mean();
    }
    for (int m = 1; m < 3; ++m)
        EXPECT_EQ(0,
                  std::memcmp(films[0].data(), films[m].data(), films[0].size() * sizeof(float)));
}

INSTANTIATE_TEST_SUITE_P(Scenes, Backends,
                         ::testing::Values(Case{"spheres_pisa", "pisa.hdr", false},
                                           // A map black but for one spot (lighting a sixth of
                                           // the film): its black mask, and compensated's few
                                           // last BSDF samples.
                                           Case{"spheres_spot", "spot1Lux.hdr", false, 0.15},
                                           Case{"bunny_grace", "grace.hdr", true},
                                           Case{"bunny_esplanade", "royal_esplanade_1k.hdr", true},
                                           Case{"bunny_overpass", "pedestrian_overpass_1k.hdr",
                                                true}),
                         [](const auto& info) { return std::string(info.param.name); });

} // namespace
