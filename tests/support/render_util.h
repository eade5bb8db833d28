// Helpers of the renderer tests: scenes built in code, renders through either back end with the
// per-pixel sample variance measured from the passes, and statistics on images.
//
// Variance: Renderer::image() is the running mean, so pass k's own sample is
// k * mean_k - (k - 1) * mean_(k-1). With the random sampler the passes are independent and
// var / n is the variance of the pixel mean; with Sobol' the passes are stratified, so the same
// figure over-estimates it (a conservative threshold).
#pragma once
#include "render/renderer.h"
#include "load/scene.h"
#include "prepare/device_scene.h"
#include "prepare/light_set.h"
#include "prepare/sis.h"
#include "test_data.h"

#include <glm/glm.hpp>

#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace ett {

// Appends a UV sphere of `segments` x segments/2 quads (two triangles each); flat shading
// normals unless `smooth`.
inline void add_sphere(et::TriangleSoup& soup, glm::vec3 c, float r, int segments, bool smooth,
                       int material) {
    const int rings = segments / 2;
    auto point = [&](int i, int j) {
        const double th = M_PI * i / rings, ph = 2 * M_PI * j / segments;
        return glm::vec3(float(std::sin(th) * std::cos(ph)), float(std::cos(th)),
                         float(std::sin(th) * std::sin(ph)));
    };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const glm::vec3 a = point(i, j), b = point(i, j + 1), d = point(i + 1, j),
                            e = point(i + 1, j + 1);
            for (const auto& tri : {std::vector<glm::vec3>{a, b, e}, {a, e, d}}) {
                glm::vec3 p[3] = {c + r * tri[0], c + r * tri[1], c + r * tri[2]};
                glm::vec3 n[3] = {tri[0], tri[1], tri[2]};
                et::add_triangle(soup, p, smooth ? n : nullptr, material);
            }
        }
}

// Appends the square of half-size h centred at c whose front faces along n.
inline void add_square(et::TriangleSoup& soup, glm::vec3 c, glm::vec3 n, float h, int material) {
    n = glm::normalize(n);
    const glm::vec3 helper = std::fabs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
    const glm::vec3 t = glm::normalize(glm::cross(helper, n)), b = glm::cross(n, t);
    const glm::vec3 q[4] = {c + h * (-t - b), c + h * (t - b), c + h * (t + b), c + h * (-t + b)};
    glm::vec3 a[3] = {q[0], q[1], q[2]}, d[3] = {q[0], q[2], q[3]};
    et::add_triangle(soup, a, nullptr, material);
    et::add_triangle(soup, d, nullptr, material);
}

inline et::Material diffuse(float albedo) {
    et::Material m;
    m.type = 0; // ETK_MAT_DIFFUSE
    m.albedo = glm::vec3(albedo);
    return m;
}

inline et::Scene base_scene(int w, int h, et::EnvMap env) {
    et::Scene s;
    s.width = w;
    s.height = h;
    s.env = std::move(env);
    s.settings.sampler = et::SamplerKind::random;
    s.settings.max_depth = 1; // direct lighting unless a test asks for more
    return s;
}

// A diffuse triangle (albedo 0.5) on y = 0 under a small sky of uneven strength (every 7th value
// 5, the others 0.2: the map's search is a real one), seen from (0, 1, 3). Settings are the
// caller's.
inline et::Scene ground_under_uneven_sky(int w, int h) {
    et::RgbImage sky = constant_image(32, 16, 0.2f);
    for (size_t i = 0; i < sky.rgb.size(); i += 7)
        sky.rgb[i] = 5.0f;
    et::Scene s = base_scene(w, h, et::make_envmap("sky", sky, {}));
    s.camera.eye = {0, 1, 3};
    s.materials.push_back(diffuse(0.5f));
    const glm::vec3 p[3] = {{-2, 0, -2}, {2, 0, -2}, {0, 0, 2}};
    const glm::vec3 n[3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    et::add_triangle(s.triangles, p, n, 0);
    return s;
}

// A closed 2 x 2 x 2 room of diffuse walls (albedo 0.7) lit through one open side by a constant
// sky, the camera inside looking at the opening's side: what the visibility strategy learns (its
// tables move the light samples towards the opening). Settings are the caller's.
inline et::Scene side_lit_room(int w, int h) {
    et::Scene s = base_scene(w, h, et::make_envmap("sky", constant_image(32, 16, 1.0f), {}));
    s.materials.push_back(diffuse(0.7f));
    const float half = 1.0f;
    add_square(s.triangles, glm::vec3(0, 0, 0), glm::vec3(0, 1, 0), half, 0);  // floor
    add_square(s.triangles, glm::vec3(0, 2, 0), glm::vec3(0, -1, 0), half, 0); // ceiling
    add_square(s.triangles, glm::vec3(-1, 1, 0), glm::vec3(1, 0, 0), half, 0);
    add_square(s.triangles, glm::vec3(1, 1, 0), glm::vec3(-1, 0, 0), half, 0);
    add_square(s.triangles, glm::vec3(0, 1, 1), glm::vec3(0, 0, -1), half, 0); // back
    s.camera.eye = {0.0f, 1.0f, 0.9f};
    s.camera.target = {0.0f, 0.8f, -1.0f};
    s.camera.fov_deg = 80.0f;
    return s;
}

// A count among the learning technique's figures (RenderStats::learning, the visibility
// strategy's: "records", "continuation_records"); 0 where nothing learns.
inline uint64_t learning_count(const et::RenderStats& st, const char* key) {
    return st.learning.is_object() && st.learning.contains(key) ? st.learning[key].get<uint64_t>()
                                                                : 0;
}
// The visibility strategy's verdict: 1 the tables stay, 0 the fallback (MIS, or compensated for
// auto) from then on, -1 not (yet) given.
inline int learning_verdict(const et::RenderStats& st) {
    if (!st.learning.is_object() || !st.learning.contains("verdict"))
        return -1;
    const std::string v = st.learning["verdict"].get<std::string>();
    return v == "tables" ? 1 : v == "none" ? -1 : 0;
}
// How it was given: "screen", "measure" or "none".
inline std::string learning_verdict_by(const et::RenderStats& st) {
    return st.learning.is_object() && st.learning.contains("verdict_by")
               ? st.learning["verdict_by"].get<std::string>()
               : "none";
}
// Its learned cells that take fewer light samples, per count.
inline std::map<float, uint64_t> learning_light_counts(const et::RenderStats& st) {
    std::map<float, uint64_t> out;
    if (st.learning.is_object() && st.learning.contains("cells_with_fewer_light_samples"))
        for (const auto& [n, cells] : st.learning["cells_with_fewer_light_samples"].items())
            out[std::stof(n)] = cells.get<uint64_t>();
    return out;
}

struct RenderResult {
    std::vector<float> mean; // RGB per pixel
    std::vector<double> var; // sample variance of one pass, per pixel and channel
    int spp = 0;
    // The visibility strategy's learned cells that take fewer light samples, per count.
    std::map<float, uint64_t> light_counts;
    std::string verdict; // a learning strategy's verdict ("tables", the fallback's name, "none")
    // Variance of the mean of pixel channel i.
    double var_mean(size_t i) const { return var[i] / spp; }
};

// Renders `spp` passes; measures the per-pass variance when `variance` (one image() read per
// pass).
// `prepared`, if given, may change the prepared scene first (e.g. its visibility options).
inline RenderResult render(const et::Scene& scene, const std::string& backend, int spp,
                           bool variance = true,
                           const std::function<void(et::DeviceScene&)>& prepared = {}) {
    et::RenderSettings st = scene.settings;
    st.backend = et::parse_backend(backend, "test");
    st.threads = 2;
    et::DeviceScene ds = et::prepare_device_scene(scene, st);
    if (prepared)
        prepared(ds);
    auto r = et::make_renderer(ds);
    RenderResult out;
    out.spp = spp;
    const size_t n = static_cast<size_t>(scene.width) * scene.height * 3;
    std::vector<double> sum(n, 0.0), sum2(n, 0.0);
    std::vector<float> prev(n, 0.0f);
    for (int k = 0; k < spp; ++k) {
        r->render_sample(static_cast<uint32_t>(k));
        if (!variance)
            continue;
        std::vector<float> cur = r->image();
        for (size_t i = 0; i < n; ++i) {
            const double x = double(cur[i]) * (k + 1) - double(prev[i]) * k;
            sum[i] += x;
            sum2[i] += x * x;
        }
        prev.swap(cur);
    }
    out.mean = r->image();
    // The film drops non-finite samples instead of writing NaN; none may occur.
    EXPECT_EQ(r->stats().nonfinite_samples, 0u) << backend << ": non-finite samples dropped";
    const et::RenderStats stats = r->stats();
    out.light_counts = learning_light_counts(stats);
    out.verdict = stats.learning.is_object() && stats.learning.contains("verdict")
                      ? stats.learning["verdict"].get<std::string>()
                      : "none";
    out.var.assign(n, 0.0);
    if (variance && spp > 1)
        for (size_t i = 0; i < n; ++i)
            out.var[i] = std::max(0.0, (sum2[i] - sum[i] * sum[i] / spp) / (spp - 1));
    return out;
}

// A renderer that has rendered samples [from, to) of `s` on `threads` threads, after resuming
// `resume` if given (the learning strategies' resume and thread-count tests). It keeps the
// prepared scene it renders alive.
struct SampleRun {
    std::unique_ptr<et::DeviceScene> scene;
    std::unique_ptr<et::Renderer> renderer;
};
// plan: what the render is said to take (Renderer::set_plan; no samples: nothing said).
inline SampleRun render_samples(const et::Scene& s, int threads, int from, int to,
                                const et::FilmSums* resume = nullptr, et::LearningPlan plan = {}) {
    et::RenderSettings st = s.settings;
    st.threads = threads;
    SampleRun run;
    run.scene = std::make_unique<et::DeviceScene>(et::prepare_device_scene(s, st));
    run.renderer = et::make_renderer(*run.scene);
    if (plan.samples > 0)
        run.renderer->set_plan([plan] { return plan; });
    if (resume)
        run.renderer->resume(*resume);
    for (int k = from; k < to; ++k)
        run.renderer->render_sample(static_cast<uint32_t>(k));
    return run;
}

inline double image_mean(const std::vector<float>& img) {
    double s = 0.0;
    for (float v : img)
        s += v;
    return img.empty() ? 0.0 : s / img.size();
}

// Two independent renders of the same expectation: z = (a - b) / sqrt(var_a / n_a + var_b /
// n_b) per pixel channel. For correct estimators mean z^2 is ~1 and |z| > 4 is rare (6e-5 for
// a Gaussian; more with the heavy tails of a poorly matched strategy, whose per-pass variance
// from a few hundred passes is itself noisy). The image means are compared with the summed
// variance.
struct Agreement {
    double mean_z2 = 0.0, max_abs_z = 0.0, frac_over_4 = 0.0;
    double mean_a = 0.0, mean_b = 0.0, mean_z = 0.0; // mean_z: of the image means
};

inline Agreement agreement(const RenderResult& a, const RenderResult& b) {
    Agreement g;
    const size_t n = a.mean.size();
    double var_sum = 0.0;
    int over = 0;
    for (size_t i = 0; i < n; ++i) {
        const double v = a.var_mean(i) + b.var_mean(i);
        var_sum += v;
        const double d = double(a.mean[i]) - b.mean[i];
        // Float rounding floor for zero-variance pixels (the background seen directly).
        const double sd = std::sqrt(v) + 1e-6 * (std::fabs(a.mean[i]) + 1e-6);
        const double z = d / sd;
        g.mean_z2 += z * z / n;
        g.max_abs_z = std::max(g.max_abs_z, std::fabs(z));
        over += std::fabs(z) > 4;
    }
    g.frac_over_4 = double(over) / n;
    g.mean_a = image_mean(a.mean);
    g.mean_b = image_mean(b.mean);
    g.mean_z = (g.mean_a - g.mean_b) / (std::sqrt(var_sum) / n + 1e-9);
    return g;
}

// Device scenes of `s` for the two strategies whose lights the host makes: a directional light
// set (12 lights) and SIS strata (6), direct lighting only, on `st`'s back end and threads.
inline std::vector<std::pair<et::Strategy, et::DeviceScene>>
light_set_and_sis_scenes(const et::Scene& s, const et::RenderSettings& st) {
    const et::LightSet set = et::make_lights_ours(s.env, 12, 1, false);
    et::SisOptions so;
    so.samples = 6;
    const et::SisResult sis = et::build_sis(s.env, so);
    std::vector<std::pair<et::Strategy, et::DeviceScene>> out;
    for (et::Strategy strategy : {et::Strategy::lights, et::Strategy::sis}) {
        et::RenderSettings t = st;
        t.strategy = strategy;
        t.max_depth = 1;
        out.emplace_back(strategy, et::prepare_device_scene(s, t, &set.lights, &sis.strata));
    }
    return out;
}

} // namespace ett
