// The OpenCL back end's lanes (host/lib/render/executor_cl.h): each lane is a command queue with
// path state of its own, running waves on a thread of its own while the others run theirs. Which
// lane renders a pixel, and in how many waves, must change nothing: the film is the same bits with
// one lane or several, one wave per lane or many, and so are the visibility strategy's tables,
// which every lane's shadow rays teach during the learning passes.
#include "render/executor_cl.h"
#include "render/renderer.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <cstring>

namespace {

// The side-lit room (render_util.h; the visibility strategy learns the opening), on OpenCL.
et::Scene lane_scene(et::Strategy strategy) {
    et::Scene s = ett::side_lit_room(23, 17);
    s.settings.strategy = strategy;
    s.settings.backend = et::Backend::opencl;
    s.settings.max_depth = 3;
    s.settings.seed = 7;
    return s;
}

struct LaneRun {
    std::vector<float> mean;
    et::RenderStats stats;
    int lanes = 0, wave = 0;
};

LaneRun render(const et::Scene& s, int lanes, int paths, int spp) {
    const et::DeviceScene ds = et::prepare_device_scene(s, s.settings);
    int used_lanes = 0, wave = 0;
    et::Renderer r(ds, [&](et::Film&) -> std::unique_ptr<et::WavefrontDevice> {
        auto d = std::make_unique<et::ClDevice>(std::make_unique<et::ClRuntime>(0), ds, paths,
                                                nullptr, lanes);
        used_lanes = d->lanes();
        wave = d->wave_size();
        return d;
    });
    for (int k = 0; k < spp; ++k)
        r.render_sample(static_cast<uint32_t>(k));
    return {r.sums().mean(), r.stats(), used_lanes, wave};
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(ClLanes, SameBitsWithAnyLaneCountAndWaveSize) {
    for (et::Strategy strategy : {et::Strategy::mis, et::Strategy::visibility}) {
        SCOPED_TRACE(et::name_of(strategy));
        const et::Scene s = lane_scene(strategy);
        // Past the visibility strategy's 64 learning passes: the learned tables are used too.
        const int spp = strategy == et::Strategy::visibility ? 68 : 6;
        const LaneRun one = render(s, 1, 0, spp);
        ASSERT_EQ(one.lanes, 1);
        EXPECT_EQ(one.wave, 23 * 17) << "one lane, one wave: the whole film";
        EXPECT_GT(ett::image_mean(one.mean), 0.0);
        EXPECT_EQ(one.stats.nonfinite_samples, 0u);
        if (strategy == et::Strategy::visibility) {
            EXPECT_GT(ett::learning_count(one.stats, "records"), 0u)
                << "nothing learned: the tables go untested";
        }
        // Two lanes (one wave each, dealt path by path), three lanes of many small waves each
        // (the last one short), two lanes of one path each.
        const int configs[][2] = {{2, 0}, {3, 29}, {2, 1}};
        for (const auto& c : configs) {
            SCOPED_TRACE("lanes " + std::to_string(c[0]) + ", paths " + std::to_string(c[1]));
            const LaneRun r = render(s, c[0], c[1], spp);
            EXPECT_EQ(r.lanes, c[0]);
            EXPECT_EQ(r.wave, c[1] > 0 ? c[1] : (23 * 17 + 1) / 2);
            EXPECT_TRUE(same_bits(one.mean, r.mean)) << "the film depends on the lanes";
            EXPECT_EQ(one.stats.shadow_rays, r.stats.shadow_rays);
            EXPECT_EQ(ett::learning_count(one.stats, "records"),
                      ett::learning_count(r.stats, "records"));
            double stage = 0.0;
            for (const auto& [name, sec] : r.stats.stage_seconds)
                stage += sec;
            EXPECT_GT(stage, 0.0) << "every lane's launches are timed";
        }
    }
}

// The default on a CPU device (PoCL, where the suite runs): a lane per compute unit, at least two,
// each on a sub-device of one compute unit where the device can be partitioned (PoCL can), in
// waves of at most 32,768 paths, as many per lane.
TEST(ClLanes, ALaneAComputeUnitOnACpuDevice) {
    et::ClRuntime rt(0);
    et::Scene s = lane_scene(et::Strategy::mis);
    if (!rt.limits().cpu) {
        // A GPU (ENVTRACE_CL_PLATFORM): one lane, which the device's own scheduler fills.
        EXPECT_EQ(et::default_cl_lanes(rt), 1);
        EXPECT_TRUE(et::one_unit_sub_devices(rt).empty());
        const et::DeviceScene ds = et::prepare_device_scene(s, s.settings);
        EXPECT_EQ(et::ClDevice(std::make_unique<et::ClRuntime>(0), ds, 0).lanes(), 1);
        GTEST_SKIP() << "not a CPU device: " << rt.device().device_name;
    }
    const int units = rt.device().compute_units;
    ASSERT_GE(units, 1);
    const std::vector<cl::Device> subs = et::one_unit_sub_devices(rt);
    EXPECT_EQ(et::default_cl_lanes(rt), subs.empty() ? 2 : static_cast<int>(subs.size()));
    const bool pocl =
        rt.device().platform_name.find("Portable Computing Language") != std::string::npos;
    if (pocl && units >= 2) {
        ASSERT_EQ(static_cast<int>(subs.size()), units);
        // Made once, kept: the same devices on every call (releasing them crashed PoCL).
        const std::vector<cl::Device> again = et::one_unit_sub_devices(rt);
        ASSERT_EQ(again.size(), subs.size());
        for (size_t k = 0; k < subs.size(); ++k)
            EXPECT_EQ(again[k](), subs[k]());
    }
    s.width = 400; // 160,000 pixels: at most 32,768 paths a wave, as many waves per lane
    s.height = 400;
    const et::DeviceScene ds = et::prepare_device_scene(s, s.settings);
    et::ClDevice d(std::make_unique<et::ClRuntime>(0), ds, 0, nullptr, 2);
    EXPECT_EQ(d.lanes(), 2);
    EXPECT_EQ(d.wave_size(), 26667); // its path state: 6 waves' worth, 3 per lane
    EXPECT_EQ(d.lanes_on_sub_devices(), !subs.empty());
    for (int k = 0; k < d.lanes() && !subs.empty(); ++k) { // each lane's queue on its sub-device
        auto& lane = dynamic_cast<et::ClLane&>(d.lane(k));
        EXPECT_EQ(lane.queue().getInfo<CL_QUEUE_DEVICE>()(), subs[k % subs.size()]()) << k;
    }
    // Paths in flight for the whole film: one wave, so one lane (a second would hold path state
    // and render nothing).
    et::ClDevice whole(std::make_unique<et::ClRuntime>(0), ds, 160000);
    EXPECT_EQ(whole.lanes(), 1);
    EXPECT_EQ(whole.wave_size(), 160000);
    EXPECT_FALSE(whole.lanes_on_sub_devices());
    // A film of one pixel: one wave of one path, one lane.
    s.width = s.height = 1;
    const et::DeviceScene tiny = et::prepare_device_scene(s, s.settings);
    et::ClDevice one(std::make_unique<et::ClRuntime>(0), tiny, 0);
    EXPECT_EQ(one.lanes(), 1);
    EXPECT_EQ(one.wave_size(), 1);
}

} // namespace
