// Light sets and SIS strata (light_set.h, sis.h) and the renders that sum over them (the
// wavefront's shade_lights stage and SIS branch): strata cover the sphere exactly once, every
// light set carries exactly the map's power, the jitter inside a stratum is uniform in solid
// angle, and renders on an unoccluded plane match their closed forms.
#include "image/image_metrics.h"
#include "kernels/directional_lights.h"
#include "render/renderer.h"
#include "prepare/light_set.h"
#include "render_util.h"
#include "prepare/sis.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>

namespace {

void expect_power_equal(const glm::dvec3& a, const glm::dvec3& b) {
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(a[c], b[c], 1e-9 * b[c]) << "channel " << c;
}

glm::dvec3 total_power(const et::LightSet& s) {
    glm::dvec3 sum(0.0);
    for (const auto& l : s.lights) {
        for (int c = 0; c < 3; ++c)
            EXPECT_GE(l.power[c], 0.0);
        EXPECT_NEAR(glm::length(l.direction), 1.0f, 1e-5f);
        sum += l.power;
    }
    return sum;
}

void check_strata(const et::EnvMap& env, const et::VoronoiStrata& v) {
    const size_t n = v.points.size();
    double sa = 0.0;
    glm::dvec3 power(0.0);
    for (size_t k = 0; k < n; ++k) {
        EXPECT_GT(v.begin[k + 1], v.begin[k]) << "cell " << k << " is empty";
        sa += v.solid_angle[k];
        power += v.power[k];
    }
    EXPECT_NEAR(sa, 4.0 * M_PI, 1e-9);
    expect_power_equal(power, et::map_power(env));
    // Every texel in exactly one cell, and in the cell of its nearest point.
    ASSERT_EQ(v.texels.size(), v.cell.size());
    std::vector<int> seen(v.cell.size(), 0);
    for (size_t k = 0; k < n; ++k)
        for (int i = v.begin[k]; i < v.begin[k + 1]; ++i) {
            ++seen[v.texels[i]];
            EXPECT_EQ(v.cell[v.texels[i]], int(k));
        }
    for (int s : seen)
        ASSERT_EQ(s, 1);
}

TEST(MapPower, ConstantMapIsFourPiTimesRadiance) {
    et::EnvMap env = et::make_envmap("const", ett::constant_image(64, 32, 2.0f), {});
    const glm::dvec3 p = et::map_power(env);
    EXPECT_NEAR(p.x, 8.0 * M_PI, 1e-9);
}

TEST(Sis, StrataCoverTheSphereOnceAndCarryTheMapsPower) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    et::EnvMap env = ett::load_map(path);
    for (int n : {1, 16, 64}) {
        et::SisOptions o;
        o.samples = n;
        et::SisResult r = et::build_sis(env, o);
        ASSERT_EQ(r.strata.points.size(), size_t(n));
        int given = 0;
        for (int s : r.level_samples)
            given += s;
        EXPECT_EQ(given, n);
        check_strata(env, r.strata);
        // Distinct points.
        std::set<std::tuple<double, double, double>> distinct;
        for (const auto& p : r.strata.points)
            distinct.insert({p.x, p.y, p.z});
        EXPECT_EQ(distinct.size(), size_t(n));
    }
}

TEST(Sis, BrightLevelsGetPointsOnAPeakedMap) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    et::EnvMap env = ett::load_map(path);
    et::SisOptions o;
    o.samples = 64;
    et::SisResult r = et::build_sis(env, o);
    // grace's few small sources hold most of the power: the levels above sigma get points.
    int bright = 0;
    for (size_t i = 1; i < r.level_samples.size(); ++i)
        bright += r.level_samples[i];
    EXPECT_GT(r.level_samples.back(), 0);
    EXPECT_GT(r.level_samples[0], 0); // and the dim rest of the sphere too
    EXPECT_GT(bright, 0);
}

TEST(LightSets, TotalPowerEqualsTheMaps) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    et::EnvMap env = ett::load_map(path);
    const glm::dvec3 target = et::map_power(env);
    for (int n : {1, 32, 128}) {
        SCOPED_TRACE(n);
        et::LightSet ours = et::make_lights_ours(env, n, 1, false);
        ASSERT_EQ(ours.lights.size(), size_t(n));
        expect_power_equal(total_power(ours), target);
        et::LightSet vor = et::make_lights_ours(env, n, 1, true);
        expect_power_equal(total_power(vor), target);
        et::LightSet sis = et::make_lights_sis(env, n, {});
        ASSERT_EQ(sis.lights.size(), size_t(n));
        expect_power_equal(total_power(sis), target);
    }
}

// Before rescaling, the shares L/(N p) are the light-sampling estimate of the map's power: the
// rescaling factor must be within the estimator's own noise of one (4 standard errors).
TEST(LightSets, SharesAreAnUnbiasedEstimateBeforeRescaling) {
    ETT_DATA_FILE(path, "envmaps/uffizi.hdr");
    et::EnvMap env = ett::load_map(path);
    const int n = 256;
    const etk::EtkEnvMap desc = env.desc();
    double sum = 0.0, sum2 = 0.0;
    for (int k = 0; k < n; ++k) {
        const etk::float2 u = etk::etk_sample_pair(ETK_SAMPLER_SOBOL, 1, 0, k, 0);
        const etk::EtkEnvSample s = etk::etk_env_sample(env.dist.table.data(), desc, u);
        ASSERT_GT(s.pdf, 0.0f);
        const double y =
            etk::etk_luma(etk::etk_env_radiance(env.image.rgb.data(), desc, s.dir)) / s.pdf;
        sum += y;
        sum2 += y * y;
    }
    const double mean = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    const glm::dvec3 p = et::map_power(env);
    const double exact = 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
    EXPECT_NEAR(mean, exact, 4.0 * sd / std::sqrt(double(n)) + 1e-6 * exact);
}

TEST(LightSets, JsonRoundTripAndBadFiles) {
    et::EnvMap env = et::make_envmap("const", ett::constant_image(64, 32, 1.0f), {});
    et::LightSet s = et::make_lights_ours(env, 8, 3, false);
    const std::string dir = ett::scratch_dir("light_sets");
    et::write_lights(dir + "/l.json", s);
    et::LightSet r = et::read_lights(dir + "/l.json");
    ASSERT_EQ(r.lights.size(), s.lights.size());
    for (size_t k = 0; k < r.lights.size(); ++k) {
        EXPECT_NEAR(glm::length(r.lights[k].direction - s.lights[k].direction), 0.0f, 1e-6f);
        EXPECT_NEAR(r.lights[k].power.y, s.lights[k].power.y, 1e-12);
    }
    {
        std::ofstream f(dir + "/bad.json");
        f << R"({"lights": [{"direction": [0, 0, 0], "power": [1, 1, 1]}]})";
    }
    EXPECT_THROW(et::read_lights(dir + "/bad.json"), et::Error);
    EXPECT_THROW(et::read_lights(dir + "/missing.json"), et::Error);
}

// Found by tools/fuzz/fuzz_light_set: keys of the wrong type used to escape as
// nlohmann::json::type_error instead of et::Error (an uncaught exception in `envtrace render`).
TEST(LightSets, KeysOfTheWrongTypeAreErrors) {
    const std::string dir = ett::scratch_dir("light_sets_types");
    const std::string light = R"({"direction": [0, 0, 1], "power": [1, 1, 1]})";
    for (const std::string& text : std::vector<std::string>{
             R"({"method": 1, "lights": [)" + light + "]}",
             R"({"power_rule": [], "lights": [)" + light + "]}",
             R"({"map": {}, "lights": [)" + light + "]}",
             R"({"lights": [{"direction": [0, 0, 1], "power": [1, 1, 1], "solid_angle": "x"}]})",
             R"({"lights": [{"direction": [0, 0, 1], "power": [1, 1, 1], "solid_angle": -1}]})",
             // Each light in range, their sum not (the render's film would overflow to black).
             R"({"lights": [{"direction": [0, 0, 1], "power": [1e13, 1, 1]},
                            {"direction": [0, 1, 0], "power": [1e13, 1, 1]}]})",
             // A count that disagrees with the lights: a file cut short or edited.
             R"({"count": 2, "lights": [)" + light + "]}"}) {
        {
            std::ofstream f(dir + "/l.json");
            f << text;
        }
        EXPECT_THROW(et::read_lights(dir + "/l.json"), et::Error) << text;
    }
}

// Jitter inside a stratum: every direction lands in a texel of that stratum, and the mean of
// cos(theta) over many stratified draws matches the cell's solid-angle average.
TEST(Sis, StratumJitterIsUniformInsideTheCell) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    et::EnvMap env = ett::load_map(path);
    et::SisOptions o;
    o.samples = 16;
    const et::VoronoiStrata v = et::build_sis(env, o).strata;
    const int w = v.width, h = v.height, m = 4096;
    for (int k = 0; k < 16; ++k) {
        double exact = 0.0, est = 0.0, est2 = 0.0;
        for (int i = v.begin[k]; i < v.begin[k + 1]; ++i) {
            const int row = v.texels[i] / w;
            const double z0 = std::cos(M_PI * row / h), z1 = std::cos(M_PI * (row + 1) / h);
            exact += et::texel_solid_angle(row, w, h) * 0.5 * (z0 + z1);
        }
        exact /= v.solid_angle[k];
        for (int j = 0; j < m; ++j) {
            const etk::float2 u = etk::etk_sample_pair(ETK_SAMPLER_RANDOM, 7, k, j, 0);
            const etk::float3 d = etk::etk_dl_stratum_direction(
                v.texels.data(), v.cdf.data(), v.begin[k], v.begin[k + 1], w, h, u);
            ASSERT_NEAR(etk::length(d), 1.0f, 1e-5f);
            const etk::float2 uv = etk::etk_dir_to_latlong(d);
            const int col = std::min(w - 1, int(uv.x * w)), row = std::min(h - 1, int(uv.y * h));
            // Allow float rounding onto a neighbouring texel at a cell border.
            bool inside = v.cell[row * w + col] == k;
            for (int dr = -1; dr <= 1 && !inside; ++dr)
                for (int dc = -1; dc <= 1 && !inside; ++dc) {
                    const int rr = std::clamp(row + dr, 0, h - 1), cc = (col + dc + w) % w;
                    inside = v.cell[rr * w + cc] == k;
                }
            ASSERT_TRUE(inside) << "stratum " << k << " sample " << j;
            est += d.y;
            est2 += double(d.y) * d.y;
        }
        const double mean = est / m, sd = std::sqrt(std::max(0.0, est2 / m - mean * mean));
        EXPECT_NEAR(mean, exact, 4.5 * sd / std::sqrt(double(m)) + 1e-6) << "stratum " << k;
    }
}

// An upward-facing diffuse square, seen from above, under nothing but the map.
et::Scene plane_scene(et::EnvMap env, float albedo) {
    et::Scene s = ett::base_scene(24, 24, std::move(env));
    s.camera.eye = glm::vec3(0, 3, 0);
    s.camera.target = glm::vec3(0, 0, 0);
    s.camera.up = glm::vec3(0, 0, -1);
    s.camera.fov_deg = 30.0f;
    s.materials.push_back(ett::diffuse(albedo));
    ett::add_square(s.triangles, glm::vec3(0), glm::vec3(0, 1, 0), 5.0f, 0);
    s.settings.max_depth = 1;
    return s;
}

// Zero variance: every pixel is exactly albedo / pi * sum_k E_k max(0, cos theta_k).
TEST(LightRender, DirectionalLightsOnAPlaneMatchTheClosedForm) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    et::EnvMap env = ett::load_map(path);
    const et::LightSet set = et::make_lights_ours(env, 32, 1, false);
    const float albedo = 0.5f;
    et::Scene scene = plane_scene(std::move(env), albedo);
    glm::dvec3 expect(0.0);
    for (const auto& l : set.lights)
        expect += l.power * double(std::max(0.0f, l.direction.y)) * (albedo / M_PI);
    et::RenderSettings st = scene.settings;
    st.strategy = et::Strategy::lights;
    st.backend = et::Backend::cpu;
    const et::DeviceScene ds = et::prepare_device_scene(scene, st, &set.lights);
    auto r = et::make_renderer(ds);
    r->render_sample(0);
    r->render_sample(1);
    const std::vector<float> img = r->image();
    for (size_t i = 0; i < img.size(); ++i)
        ASSERT_NEAR(img[i], expect[i % 3], 1e-4 * expect[i % 3] + 1e-7) << "value " << i;
}

// SIS is unbiased when L is constant inside each stratum: a constant map of radiance L over an
// unoccluded diffuse plane gives albedo * L (within 5 standard errors of the pixel mean).
TEST(LightRender, SisOnAConstantMapIsUnbiased) {
    const float L = 1.5f, albedo = 0.6f;
    et::EnvMap env = et::make_envmap("const", ett::constant_image(64, 32, L), {});
    et::SisOptions o;
    o.samples = 16;
    const et::SisResult sis = et::build_sis(env, o);
    et::Scene scene = plane_scene(std::move(env), albedo);
    et::RenderSettings st = scene.settings;
    st.strategy = et::Strategy::sis;
    st.backend = et::Backend::cpu;
    const et::DeviceScene ds = et::prepare_device_scene(scene, st, nullptr, &sis.strata);
    auto r = et::make_renderer(ds);
    for (uint32_t s = 0; s < 64; ++s)
        r->render_sample(s);
    const std::vector<float> img = r->image();
    double sum = 0.0, sum2 = 0.0;
    for (size_t i = 1; i < img.size(); i += 3) {
        sum += img[i];
        sum2 += double(img[i]) * img[i];
    }
    const double n = img.size() / 3, mean = sum / n;
    const double sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    EXPECT_NEAR(mean, albedo * L, 5.0 * sd / std::sqrt(n) + 1e-5);
}

TEST(ImageMetrics, KnownValuesMaskAndSizeMismatch) {
    et::RgbImage b = ett::constant_image(4, 2, 1.0f), a = ett::constant_image(4, 2, 2.0f);
    et::ImageErrors e = et::compare_images(a, b);
    EXPECT_EQ(e.pixels, 8u);
    EXPECT_DOUBLE_EQ(e.rmse, 1.0);
    EXPECT_DOUBLE_EQ(e.l2, 1.0);
    EXPECT_NEAR(e.rel_mse, 1.0 / (1.0 + et::kRelMseEpsilon), 1e-12);
    EXPECT_DOUBLE_EQ(et::compare_images(b, b).l2, 0.0);
    std::vector<unsigned char> mask(8, 0);
    mask[3] = 1;
    a.at(0, 0)[0] = 100.0f; // outside the mask
    e = et::compare_images(a, b, mask);
    EXPECT_EQ(e.pixels, 1u);
    EXPECT_DOUBLE_EQ(e.rmse, 1.0);
    EXPECT_THROW(et::compare_images(ett::constant_image(4, 4, 1.0f), b), et::Error);
}

} // namespace
