// What the host asks of an OpenCL device before using it: work-group sizes from the
// kernel and device, every buffer checked against the largest allocation and their sum against
// global memory (with messages naming the buffer and the sizes), big-endian devices refused,
// and profiling events released as a render goes rather than kept for its whole length.
#include "opencl/opencl_runtime.h"
#include "render/executor_cl.h"
#include "render/renderer.h"
#include "render_util.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <string>

namespace {

et::DeviceLimits limits(uint64_t max_alloc, uint64_t global_mem) {
    et::DeviceLimits l;
    l.max_alloc = max_alloc;
    l.global_mem = global_mem;
    l.max_work_group = 1024;
    l.max_work_item_x = 1024;
    return l;
}

using ett::error_of;

TEST(DeviceLimits, LocalSizeRespectsKernelDeviceAndPreferredMultiple) {
    et::DeviceLimits l = limits(1 << 30, 1 << 30);
    EXPECT_EQ(et::choose_local_size(4096, 8, l), 64u); // PoCL-like: the target
    EXPECT_EQ(et::choose_local_size(48, 16, l), 48u);  // kernel limit, a multiple of 16
    EXPECT_EQ(et::choose_local_size(40, 16, l), 32u);  // rounded down to the multiple
    EXPECT_EQ(et::choose_local_size(12, 32, l), 12u);  // multiple larger than what fits
    EXPECT_EQ(et::choose_local_size(1, 1, l), 1u);     // a device running one item a group
    EXPECT_EQ(et::choose_local_size(256, 32, l, 256), 256u);
    l.max_work_group = 128;
    EXPECT_EQ(et::choose_local_size(256, 32, l, 256), 128u);
    l.max_work_item_x = 96;
    EXPECT_EQ(et::choose_local_size(256, 32, l, 256), 96u);
}

TEST(DeviceLimits, BufferOverTheLargestAllocationIsNamedWithSizes) {
    const std::string msg = error_of([] {
        et::check_buffer_sizes({{"nodes", 1000}, {"env_texels", 5000}, {"film_sum", 10}},
                               limits(4096, 1 << 20), "Test Device");
    });
    EXPECT_NE(msg.find("'Test Device'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("buffer env_texels needs 5000 bytes"), std::string::npos) << msg;
    EXPECT_NE(msg.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE = 4096 bytes"), std::string::npos) << msg;
}

TEST(DeviceLimits, BuffersOverGlobalMemoryAreRefusedWithTheTotal) {
    const std::string msg = error_of([] {
        et::check_buffer_sizes({{"nodes", 3000}, {"tris", 4000}, {"ray_o", 2000}},
                               limits(4096, 8999), "Test Device");
    });
    EXPECT_NE(msg.find("need 9000 bytes"), std::string::npos) << msg;
    EXPECT_NE(msg.find("tris, 4000 bytes"), std::string::npos) << "names the largest: " << msg;
    EXPECT_NE(msg.find("CL_DEVICE_GLOBAL_MEM_SIZE = 8999 bytes"), std::string::npos) << msg;
    EXPECT_NO_THROW(et::check_buffer_sizes({{"nodes", 3000}, {"tris", 4000}, {"ray_o", 2000}},
                                           limits(4096, 9000), "Test Device"));
}

TEST(DeviceLimits, BigEndianDeviceIsRefused) {
    et::DeviceLimits l = limits(1 << 30, 1 << 30);
    EXPECT_NO_THROW(et::check_device_usable(l, "Little"));
    l.little_endian = false;
    const std::string msg = error_of([&] { et::check_device_usable(l, "Big Iron"); });
    EXPECT_NE(msg.find("'Big Iron' is big-endian"), std::string::npos) << msg;
}

// Sets an environment variable for its lifetime.
class ScopedEnv {
  public:
    ScopedEnv(const char* name, const std::string& value) : name_(name) {
        setenv(name, value.c_str(), 1);
    }
    ~ScopedEnv() { unsetenv(name_); }

  private:
    const char* name_;
};

// A tiny film under a 256 x 128 map: the map's texels are by far the largest buffer.
et::DeviceScene big_map_scene(et::Scene& s) {
    s = ett::base_scene(4, 4, et::make_envmap("big", ett::constant_image(256, 128, 1.0f), {}));
    ett::add_sphere(s.triangles, glm::vec3(0, 0, -3), 1.0f, 8, false, 0);
    s.materials.push_back(ett::diffuse(0.5f));
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::opencl;
    // A strategy without learned tables, whose 32 MiB would be the largest buffer.
    st.strategy = et::Strategy::compensated;
    return et::prepare_device_scene(s, st);
}

TEST(DeviceLimits, RendererChecksSceneBuffersAgainstTheDevice) {
    et::Scene s;
    const et::DeviceScene ds = big_map_scene(s);
    const uint64_t texels = ds.env_texels.size() * sizeof(float);
    ASSERT_EQ(texels, 256u * 128u * 3u * 4u);
    ASSERT_GT(texels, ds.env_dist.size() * sizeof(float)) << "test premise: texels largest";
    {
        ScopedEnv env("ENVTRACE_CL_MAX_ALLOC", std::to_string(texels - 1));
        const std::string msg = error_of([&] { et::make_renderer(ds); });
        EXPECT_NE(msg.find("buffer env_texels needs " + std::to_string(texels) + " bytes"),
                  std::string::npos)
            << msg;
        EXPECT_NE(msg.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE = " + std::to_string(texels - 1)),
                  std::string::npos)
            << msg;
    }
    {
        // Room for the scene and film, none for a single path.
        ScopedEnv env("ENVTRACE_CL_GLOBAL_MEM", std::to_string(texels + 100));
        const std::string msg = error_of([&] { et::make_renderer(ds); });
        EXPECT_NE(msg.find("in all (the largest, env_texels"), std::string::npos) << msg;
        EXPECT_NE(msg.find("CL_DEVICE_GLOBAL_MEM_SIZE = " + std::to_string(texels + 100)),
                  std::string::npos)
            << msg;
    }
    {
        ScopedEnv env("ENVTRACE_CL_MAX_ALLOC", "lots");
        EXPECT_NE(error_of([&] { et::make_renderer(ds); }).find("ENVTRACE_CL_MAX_ALLOC"),
                  std::string::npos);
    }
    // Within the limits it renders.
    auto r = et::make_renderer(ds);
    r->render_sample(0);
    EXPECT_GT(ett::image_mean(r->image()), 0.0);
}

// Forwards to the device and records the most events held after any launch.
class Watch : public et::StageExecutor {
  public:
    explicit Watch(et::ClDevice& d) : d_(d), lane_(d.lane(0)) {}
    void bind_queues(bool swapped) override { lane_.bind_queues(swapped); }
    void reset_counters() override { lane_.reset_counters(); }
    void read_counters(uint32_t* c) override { lane_.read_counters(c); }
    void read_fields(int n, const std::vector<et::FieldRead>& reads) override {
        lane_.read_fields(n, reads);
    }
    void launch(int stage, int n, const etk::EtkParams& p) override {
        lane_.launch(stage, n, p);
        ++launches;
        most = std::max(most, d_.pending_events());
    }
    size_t most = 0, launches = 0;

  private:
    et::ClDevice& d_;
    et::StageExecutor& lane_;
};

TEST(DeviceLimits, EventsAreReleasedWithinABounce) {
    et::Scene s;
    const et::DeviceScene ds = big_map_scene(s);
    // 2 paths in flight for 16 pixels: 8 waves in one pass, each several bounces.
    et::ClDevice device(std::make_unique<et::ClRuntime>(0), ds, 2);
    ASSERT_EQ(device.wave_size(), 2);
    Watch watch(device);
    et::RayCounts counts;
    etk::EtkParams p = ds.params;
    p.sample_index = 0;
    for (int first = 0; first < 16; first += 2)
        et::run_wave(watch, p, first, 2, counts);
    device.finish();
    EXPECT_GT(watch.launches, 30u);
    EXPECT_LE(watch.most, 3u) << "events of finished launches must be released as the render goes";
    EXPECT_EQ(device.pending_events(), 0u);
    const auto times = device.stage_seconds();
    double total = 0.0;
    for (const auto& [name, sec] : times)
        total += sec;
    EXPECT_GT(total, 0.0) << "profiling times are still collected";
    for (size_t local : device.local_sizes()) {
        EXPECT_GE(local, 1u);
        EXPECT_LE(local, 64u);
    }
}

} // namespace

namespace {

// `envtrace devices --kernels`: every stage kernel of wavefront.cl (and zero_words) with what
// the device reports and a launch size the device accepts.
TEST(DeviceLimits, StageKernelInfoCoversEveryStageWithAValidLaunchSize) {
    et::ClRuntime rt(0);
    const std::vector<et::StageKernelInfo> info = et::stage_kernel_info(rt);
    ASSERT_EQ(info.size(), static_cast<size_t>(etk::ETK_STAGE_COUNT) + 1);
    for (int s = 0; s < etk::ETK_STAGE_COUNT; ++s)
        EXPECT_EQ(info[s].name, et::stage_name(s));
    EXPECT_EQ(info.back().name, "zero_words");
    for (const et::StageKernelInfo& k : info) {
        SCOPED_TRACE(k.name);
        EXPECT_GE(k.local, 1u);
        EXPECT_LE(k.local, et::kStageLocalTarget);
        EXPECT_LE(k.local, k.work_group_size);
        EXPECT_LE(k.local, rt.limits().max_work_group);
        if (k.preferred_multiple > 1 && k.local >= k.preferred_multiple) {
            EXPECT_EQ(k.local % k.preferred_multiple, 0u);
        }
    }
}

} // namespace
