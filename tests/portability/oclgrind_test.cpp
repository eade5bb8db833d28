// Oclgrind as a second OpenCL implementation: every program of kernels/ runs on Oclgrind's
// simulated device and on PoCL in one process, and the results are compared bit for bit —
// tiny renders of the shipped scene kinds (wavefront.cl: every stage kernel), the sampler
// (sampler_test.cl), environment-map sampling (envmap_sample.cl) and BVH traversal
// (bvh_test.cl). ctest runs this under tests/portability/oclgrind_run.sh, which turns on
// Oclgrind's API, data-race and uninitialised-value checks and fails on any report.
//
// Platforms are chosen with ENVTRACE_CL_PLATFORM (opencl_runtime.h); OCL_ICD_VENDORS (set by
// ctest) names a folder holding both the system's ICDs and Oclgrind's.
#include "kernels/bvh.h"
#include "kernels/sampler.h"
#include "load/scene.h"
#include "opencl/opencl_runtime.h"
#include "prepare/device_scene.h"
#include "render/env_sampling.h"
#include "render/renderer.h"
#include "render_util.h"
#include "bvh_trace.h"
#include "test_data.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

const char* kOclgrind = "oclgrind";
const char* kPocl = "portable computing language";

// Sets ENVTRACE_CL_PLATFORM for its lifetime.
class ScopedPlatform {
  public:
    explicit ScopedPlatform(const char* platform) {
        if (const char* old = std::getenv("ENVTRACE_CL_PLATFORM")) {
            had_ = true;
            old_ = old;
        }
        setenv("ENVTRACE_CL_PLATFORM", platform, 1);
    }
    ~ScopedPlatform() {
        if (had_)
            setenv("ENVTRACE_CL_PLATFORM", old_.c_str(), 1);
        else
            unsetenv("ENVTRACE_CL_PLATFORM");
    }

  private:
    bool had_ = false;
    std::string old_;
};

// The two runtimes, kept for the whole program (building a context per test would be slow).
std::unique_ptr<et::ClRuntime> g_oclgrind, g_pocl;

// Releases them while the program still runs, not in static destruction at exit: one CI run of
// oclgrind_control_reports_errors was aborted by glibc ("corrupted double-linked list") after
// every test had passed (not reproduced in 27 further runs). Releasing the contexts before
// exit takes them out of the unordered teardown of static objects across libraries
// (Oclgrind's, the ICD loader's), the likeliest cause.
class ReleaseRuntimes : public ::testing::Environment {
  public:
    void TearDown() override {
        g_oclgrind.reset();
        g_pocl.reset();
    }
};
const auto* const kReleaseRuntimes = ::testing::AddGlobalTestEnvironment(new ReleaseRuntimes);

et::ClRuntime& runtime_on(const char* platform) {
    std::unique_ptr<et::ClRuntime>& rt = platform == kOclgrind ? g_oclgrind : g_pocl;
    if (!rt) {
        ScopedPlatform p(platform);
        rt = std::make_unique<et::ClRuntime>(0);
    }
    return *rt;
}

TEST(Oclgrind, PlatformIsSelectableByName) {
    // Not a skip: ctest points OCL_ICD_VENDORS at a folder with Oclgrind's ICD, so a missing
    // platform is a broken set-up.
    et::ClRuntime& o = runtime_on(kOclgrind);
    EXPECT_NE(o.device().platform_name.find("Oclgrind"), std::string::npos)
        << o.device().platform_name;
    et::ClRuntime& p = runtime_on(kPocl);
    EXPECT_NE(p.device().platform_name.find("Portable Computing Language"), std::string::npos)
        << p.device().platform_name;
    ScopedPlatform none("no such platform");
    try {
        et::list_devices();
        FAIL() << "a platform filter that matches nothing was accepted";
    } catch (const et::Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("ENVTRACE_CL_PLATFORM='no such platform'"), std::string::npos) << msg;
        EXPECT_NE(msg.find("Oclgrind"), std::string::npos) << "should list the platforms: " << msg;
    }
}

// ---- sampler_test.cl: etk_sample_pair for a run of indices -------------------------------

std::vector<float> sample_pairs(et::ClRuntime& rt, int sampler, uint32_t first, int n) {
    cl::Program program = ett::build_test_kernel(rt, "sampler_test.cl");
    cl::Kernel k(program, "sample_pairs");
    cl::Buffer out(rt.context(), CL_MEM_WRITE_ONLY, sizeof(float) * 2 * n);
    k.setArg(0, sampler);
    k.setArg(1, 0x1234567u);
    k.setArg(2, 77u);
    k.setArg(3, first);
    k.setArg(4, 3u);
    k.setArg(5, n);
    k.setArg(6, out);
    const size_t local = et::choose_local_size(k, rt.device().device, rt.limits());
    rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((n + local - 1) / local * local),
                                    cl::NDRange(local));
    std::vector<float> v(2 * static_cast<size_t>(n));
    rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, v.size() * sizeof(float), v.data());
    return v;
}

TEST(Oclgrind, SamplerEqualsPoclAndHost) {
    const int n = 200; // not a multiple of the work-group size: the tail is exercised too
    for (int sampler : {ETK_SAMPLER_SOBOL, ETK_SAMPLER_RANDOM})
        for (uint32_t first : {0u, 0xffffff00u}) {
            const std::vector<float> o = sample_pairs(runtime_on(kOclgrind), sampler, first, n);
            const std::vector<float> p = sample_pairs(runtime_on(kPocl), sampler, first, n);
            ASSERT_EQ(0, std::memcmp(o.data(), p.data(), o.size() * sizeof(float)))
                << "sampler " << sampler << " first " << first;
            for (int i = 0; i < n; ++i) {
                const etk::float2 h = etk::etk_sample_pair(sampler, 0x1234567u, 77u, first + i, 3u);
                ASSERT_EQ(etk::as_uint(o[2 * i]), etk::as_uint(h.x)) << i;
                ASSERT_EQ(etk::as_uint(o[2 * i + 1]), etk::as_uint(h.y)) << i;
            }
        }
}

// ---- envmap_sample.cl: map samples from uniforms and from the sampler ----------------------

TEST(Oclgrind, EnvironmentSamplingEqualsPocl) {
    ETT_DATA_FILE(path, "envmaps/grace.hdr");
    const et::EnvMap env = ett::load_map(path);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    std::vector<float> uniforms(2 * 300);
    for (float& u : uniforms)
        u = uni(rng);
    uniforms[0] = 0.0f;
    uniforms[1] = ETK_ONE_MINUS_EPS;
    et::EnvSamplerCL o(runtime_on(kOclgrind), env), p(runtime_on(kPocl), env);
    const auto a = o.sample_uniforms(uniforms), b = p.sample_uniforms(uniforms);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])))
        << "samples from uniforms differ";
    const auto c = o.sample_sequence(ETK_SAMPLER_SOBOL, 9u, 4u, 0u, 256);
    const auto d = p.sample_sequence(ETK_SAMPLER_SOBOL, 9u, 4u, 0u, 256);
    ASSERT_EQ(c.size(), d.size());
    EXPECT_EQ(0, std::memcmp(c.data(), d.data(), c.size() * sizeof(c[0])))
        << "samples from the sampler differ";
}

// ---- bvh_test.cl: closest and any hits through a scene's BVH -------------------------------

std::vector<etk::float4> trace(et::ClRuntime& rt, const et::DeviceScene& ds,
                               const std::vector<etk::float4>& org,
                               const std::vector<etk::float4>& dir, int any_hit) {
    return ett::trace_bvh_kernel(rt, ds.nodes, ds.packets, org, dir, any_hit);
}

et::DeviceScene prepare(const std::string& scene_file, int w, int h, et::Scene* keep = nullptr) {
    et::Scene s = et::load_scene(scene_file);
    s.width = w;
    s.height = h;
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::opencl;
    et::DeviceScene ds = et::prepare_device_scene(s, st);
    if (keep)
        *keep = std::move(s);
    return ds;
}

TEST(Oclgrind, BvhTraversalEqualsPoclAndHost) {
    const std::string scene = std::string(ENVTRACE_SOURCE_DIR) + "/scenes/cornell_box.json";
    ETT_DATA_FILE(mesh, "meshes/cornell_box.obj");
    const et::DeviceScene ds = prepare(scene, 4, 4);
    ASSERT_GT(ds.packets.size(), 0u);
    // Rays from inside the box's bounds towards random directions, some short (tmax).
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> pos(0.0f, 550.0f), d(-1.0f, 1.0f), t(10.0f, 900.0f);
    std::vector<etk::float4> org, dir;
    for (int i = 0; i < 150; ++i) {
        org.push_back(etk::make_float4(pos(rng), pos(rng), pos(rng) - 100.0f, t(rng)));
        etk::float3 v = etk::normalize(etk::make_float3(d(rng), d(rng), d(rng)));
        dir.push_back(etk::make_float4(v.x, v.y, v.z, 0.0f));
    }
    for (int any_hit : {0, 1}) {
        const auto a = trace(runtime_on(kOclgrind), ds, org, dir, any_hit);
        const auto b = trace(runtime_on(kPocl), ds, org, dir, any_hit);
        EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])))
            << "any_hit " << any_hit;
        int hits = 0;
        for (size_t i = 0; i < org.size(); ++i) {
            etk::EtkHit hh;
            const int hit = etk::etk_bvh_traverse(
                ds.nodes.data(), ds.packets.data(), etk::make_float3(org[i].x, org[i].y, org[i].z),
                etk::make_float3(dir[i].x, dir[i].y, dir[i].z), org[i].w, any_hit, &hh);
            hits += hit ? 1 : 0;
            const int prim = hit ? hh.prim : -1;
            EXPECT_EQ(static_cast<int>(etk::as_uint(a[i].y)), prim) << "ray " << i;
            if (hit && !any_hit) {
                EXPECT_EQ(etk::as_uint(a[i].x), etk::as_uint(hh.t)) << "ray " << i;
                EXPECT_EQ(etk::as_uint(a[i].z), etk::as_uint(hh.b1)) << "ray " << i;
                EXPECT_EQ(etk::as_uint(a[i].w), etk::as_uint(hh.b2)) << "ray " << i;
            }
        }
        EXPECT_GT(hits, 20) << "the rays should hit the box";
        EXPECT_LT(hits, 150) << "some rays should end before a wall (tmax)";
    }
}

// ---- wavefront.cl: tiny renders of the shipped scenes ---------------------------------------

et::FilmSums render_on(const char* platform, const et::DeviceScene& ds, int spp, uint64_t* rays) {
    ScopedPlatform p(platform);
    auto r = et::make_renderer(ds);
    for (int k = 0; k < spp; ++k)
        r->render_sample(static_cast<uint32_t>(k));
    EXPECT_EQ(r->stats().nonfinite_samples, 0u) << platform;
    *rays = r->stats().rays();
    return r->sums();
}

void expect_same_films(const et::DeviceScene& ds, int spp) {
    uint64_t rays_o = 0, rays_p = 0;
    const et::FilmSums o = render_on(kOclgrind, ds, spp, &rays_o);
    const et::FilmSums p = render_on(kPocl, ds, spp, &rays_p);
    EXPECT_EQ(rays_o, rays_p);
    EXPECT_GT(rays_o, 0u);
    ASSERT_EQ(o.pixels(), p.pixels());
    double sum = 0.0;
    for (float v : p.mean())
        sum += v;
    EXPECT_GT(sum, 0.0) << "a black image proves little";
    // Exact sums of the samples and of their squares: equal iff every sample is.
    EXPECT_TRUE(o == p) << "film sums differ between Oclgrind and PoCL";
}

struct SceneCase {
    const char* file;
    const char* data; // a data file it needs ("" for none)
};

class OclgrindScenes : public ::testing::TestWithParam<SceneCase> {};

TEST_P(OclgrindScenes, TinyRenderEqualsPoclBitForBit) {
    const SceneCase c = GetParam();
    if (*c.data && ett::data_file(c.data).empty())
        GTEST_SKIP() << c.data << " not found: set ENVTRACE_DATA to ../shared/data";
    // 10 x 6 pixels, the scene's own depth, strategy and materials; 2 samples per pixel.
    const et::DeviceScene ds =
        prepare(std::string(ENVTRACE_SOURCE_DIR) + "/scenes/" + c.file, 10, 6);
    expect_same_films(ds, 2);
}

INSTANTIATE_TEST_SUITE_P(
    Shipped, OclgrindScenes,
    ::testing::Values(SceneCase{"default.json", ""}, SceneCase{"textures.json", ""},
                      SceneCase{"textured_cube.json", ""},
                      SceneCase{"cornell_box.json", "meshes/cornell_box.obj"},
                      SceneCase{"matpreview.json", "envmaps/museum_wells6.exr"},
                      SceneCase{"bunny_grace.json", "envmaps/grace.hdr"},
                      SceneCase{"glass.json", "envmaps/royal_esplanade_1k.hdr"}),
    [](const auto& info) {
        std::string n = info.param.file;
        return n.substr(0, n.find('.'));
    });

TEST(Oclgrind, LightSetAndSisRenderEqualPocl) {
    // The shade_lights stage: a directional light set and SIS strata, direct lighting.
    et::Scene s;
    const std::string file = std::string(ENVTRACE_SOURCE_DIR) + "/scenes/default.json";
    prepare(file, 8, 6, &s);
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::opencl;
    for (const auto& [strategy, ds] : ett::light_set_and_sis_scenes(s, st)) {
        SCOPED_TRACE(et::name_of(strategy));
        expect_same_films(ds, 2);
    }
}

// A paths-in-flight count smaller than the film: several waves per pass, queues reused; the
// queue sizes read by the host or kept on the device.
void expect_several_waves_equal_pocl(et::QueueCounts counts) {
    et::Scene s;
    prepare(std::string(ENVTRACE_SOURCE_DIR) + "/scenes/default.json", 9, 7, &s);
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::opencl;
    st.paths = 20;
    st.queue_counts = counts;
    const et::DeviceScene ds = et::prepare_device_scene(s, st);
    expect_same_films(ds, 1);
}

TEST(Oclgrind, SeveralWavesPerPassEqualPocl) {
    expect_several_waves_equal_pocl(et::QueueCounts::host);
}

// With the queue sizes kept on the device (a GPU's default): every stage launched for the whole
// wave and its surplus work-items returning, the counters stepped between bounces by one
// work-item (no races, no reads past a queue).
TEST(Oclgrind, SeveralWavesCountedOnTheDeviceEqualPocl) {
    expect_several_waves_equal_pocl(et::QueueCounts::device);
}

} // namespace

namespace {

// The control, run by ctest with oclgrind_run.sh --expect: a kernel that reads memory nobody
// wrote and whose work-items all write different values to one address must be reported, or the
// clean runs above prove nothing.
TEST(OclgrindControl, KernelWithErrorsRuns) {
    et::ClRuntime& rt = runtime_on(kOclgrind);
    const char* src = "__kernel void control(__global const float* in, __global float* out) {\n"
                      "    out[0] = in[get_global_id(0)] + (float)get_global_id(0);\n"
                      "}\n";
    cl::Program program = rt.build_source("control.cl", src);
    cl::Kernel k(program, "control");
    cl::Buffer in(rt.context(), CL_MEM_READ_ONLY, 8 * sizeof(float));
    cl::Buffer out(rt.context(), CL_MEM_WRITE_ONLY, sizeof(float));
    k.setArg(0, in);
    k.setArg(1, out);
    rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(8), cl::NDRange(4));
    float v = 0.0f;
    rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof v, &v);
}

} // namespace
