// The wavefront schedule (host/lib/render/schedule.h): a pass over every pixel, and a measuring
// pass over every pixel_stride-th pixel only -- the same paths, bit for bit, where it renders, and
// nothing anywhere else, whatever the waves' size.
#include "render/executor_cl.h"
#include "render/executor_cpu.h"
#include "render/film.h"
#include "render/renderer.h"
#include "render/schedule.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <thread>
#include <vector>

namespace {

et::DeviceScene strided_scene(int width = 13, int height = 7) {
    const et::Scene s = ett::ground_under_uneven_sky(width, height);
    et::RenderSettings st = s.settings;
    st.max_depth = 3;
    st.strategy = et::Strategy::compensated;
    return et::prepare_device_scene(s, st);
}

// One pass of sample 3 with the given stride into a fresh film, in waves of `wave` paths, on the
// native back end on 2 threads (or on OpenCL's first platform, the film handed back; `lanes`: 0
// for the device's default).
et::Film strided_pass(const et::DeviceScene& ds, int stride, int wave, bool opencl = false,
                      int lanes = 0) {
    et::Film film(ds.params.width, ds.params.height);
    std::unique_ptr<et::WavefrontDevice> d;
    if (opencl)
        d = std::make_unique<et::ClDevice>(std::make_unique<et::ClRuntime>(0), ds, wave, nullptr,
                                           lanes);
    else
        d = std::make_unique<et::CpuDevice>(ds, film, 2, wave);
    et::WavefrontDevice& device = *d;
    device.clear_film(false);
    etk::EtkParams p = ds.params;
    p.sample_index = 3;
    p.pixel_stride = stride;
    const et::RayCounts c = et::run_pass(device, p);
    EXPECT_FALSE(c.abandoned);
    EXPECT_EQ(c.camera, (ds.params.width * ds.params.height + stride - 1) / stride);
    device.download_film(film, false);
    return film;
}

bool same_pixel(const et::Film& a, const et::Film& b, size_t i) {
    return std::memcmp(&a.film_sum[i], &b.film_sum[i], sizeof(a.film_sum[i])) == 0;
}

TEST(Schedule, AStridedPassRendersEveryStrideThPixelAsTheFullPassDoes) {
    const et::DeviceScene ds = strided_scene();
    ASSERT_EQ(ds.params.pixel_stride, 1);
    const et::Film full = strided_pass(ds, 1, 5);
    const size_t pixels = full.pixels();
    for (size_t i = 0; i < pixels; ++i)
        ASSERT_GT(full.film_sum[i].w, 0.0f) << i;
    for (int stride : {2, 3, 4}) {
        for (int wave : {5, 64}) {
            SCOPED_TRACE(testing::Message() << "stride " << stride << ", wave " << wave);
            const et::Film part = strided_pass(ds, stride, wave);
            for (size_t i = 0; i < pixels; ++i) {
                if (i % static_cast<size_t>(stride) == 0)
                    EXPECT_TRUE(same_pixel(part, full, i)) << "pixel " << i;
                else
                    EXPECT_EQ(part.film_sum[i].w, 0.0f) << "pixel " << i;
            }
        }
    }
}

// The kernels' generate stage maps slots to pixels: on OpenCL the same subset, the same bits (at
// depth 3 the native and PoCL paths may part at a grazing hit, backends_test.cpp; this scene
// has none).
TEST(Schedule, AStridedPassIsTheSameOnOpenCl) {
    const et::DeviceScene ds = strided_scene();
    const et::Film native = strided_pass(ds, 3, 7);
    const et::Film cl = strided_pass(ds, 3, 7, true);
    for (size_t i = 0; i < native.pixels(); ++i)
        EXPECT_TRUE(same_pixel(cl, native, i)) << "pixel " << i;
}

// Passes of several waves a lane end in waves shrunk to a share of what is left (WaveDealer): the
// film the same bits as one whole-film wave, on both back ends. Two lanes: 40,960 paths in waves
// of 12,000 are dealt as 10,240, 7,680, 5,760, 4,320, then 4,096 (kTailWave) thrice and 672; the
// strided pass's 20,480 in waves of 6,000 as 5,120, 4,096 thrice and 3,072.
TEST(Schedule, ShrinkingTailWavesGiveTheSameFilm) {
    const et::DeviceScene ds = strided_scene(256, 160);
    for (bool opencl : {false, true}) {
        SCOPED_TRACE(opencl ? "opencl" : "native");
        for (int stride : {1, 2}) {
            const et::Film whole = strided_pass(ds, stride, 40960, opencl);
            // Two lanes on every host, as natively: with more, a pass of one wave a lane is
            // dealt path by path and no wave shrinks.
            const et::Film tail = strided_pass(ds, stride, stride == 1 ? 12000 : 6000, opencl, 2);
            size_t differ = 0;
            for (size_t i = 0; i < whole.pixels(); ++i)
                differ += !same_pixel(whole, tail, i);
            EXPECT_EQ(differ, 0u) << "stride " << stride;
        }
    }
}

// One pass of sample 2 on OpenCL in waves of `wave` paths, the queue sizes read by the host or
// kept on the device (RenderSettings::queue_counts): its film and ray counts.
struct ClPass {
    et::Film film;
    et::RayCounts counts;
};
ClPass cl_pass(const et::DeviceScene& ds, int wave) {
    et::ClDevice device(std::make_unique<et::ClRuntime>(0), ds, wave);
    EXPECT_EQ(device.lane(0).counts_on_device(),
              ds.settings.queue_counts == et::QueueCounts::device);
    ClPass out{et::Film(ds.params.width, ds.params.height), {}};
    device.clear_film(false);
    etk::EtkParams p = ds.params;
    p.sample_index = 2;
    out.counts = et::run_pass(device, p);
    device.download_film(out.film, false);
    return out;
}

// A wave whose queue sizes stay on the device enqueues its bounces without reading them back:
// the same film bits and ray counts as the host's reads, whatever the waves' size. At depth 40
// without Russian roulette, paths outlive the bounces the device counts alone and the host takes
// the wave on: in a closed room every path takes all 40 bounces.
TEST(Schedule, QueueCountsOnTheDeviceGiveTheSamePasses) {
    et::Scene open = ett::side_lit_room(12, 9);
    et::Scene closed = open;
    ett::add_square(closed.triangles, glm::vec3(0, 1, -1), glm::vec3(0, 0, 1), 1.0f, 0);
    for (const et::Scene* s : {&open, &closed}) {
        const bool shut = s == &closed;
        for (int depth : {3, 40}) {
            et::RenderSettings st = s->settings;
            st.max_depth = depth;
            st.rr_depth = depth;
            st.strategy = et::Strategy::mis;
            ClPass pass[2];
            for (int wave : {17, 108}) {
                SCOPED_TRACE(testing::Message() << (shut ? "closed" : "open") << " room, depth "
                                                << depth << ", wave " << wave);
                for (int k = 0; k < 2; ++k) {
                    st.queue_counts = k ? et::QueueCounts::device : et::QueueCounts::host;
                    pass[k] = cl_pass(et::prepare_device_scene(*s, st), wave);
                }
                const et::RayCounts &h = pass[0].counts, &d = pass[1].counts;
                EXPECT_EQ(d.camera, h.camera);
                EXPECT_EQ(d.continuation, h.continuation);
                EXPECT_EQ(d.shadow, h.shadow);
                EXPECT_EQ(d.shaded, h.shaded);
                EXPECT_EQ(d.nonfinite, 0u);
                if (shut) { // nothing leaves: every path to the last bounce
                    EXPECT_EQ(h.continuation, uint64_t(depth) * h.camera);
                }
                double lit = 0.0;
                for (size_t i = 0; i < h.camera; ++i) {
                    EXPECT_TRUE(same_pixel(pass[1].film, pass[0].film, i)) << "pixel " << i;
                    lit += pass[0].film.film_sum[i].x;
                }
                EXPECT_EQ(lit > 0.0, !shut);
            }
        }
    }
}

// The same through the renderer, with the visibility strategy's learning (records summed on the
// device, table updates, the verdict's strided passes): the same film bits either way.
TEST(Schedule, QueueCountsOnTheDeviceKeepALearningRendersBits) {
    const et::Scene s = ett::side_lit_room(12, 9);
    std::vector<float> films[2];
    for (int k = 0; k < 2; ++k) {
        et::RenderSettings st = s.settings;
        st.max_depth = 3;
        st.strategy = et::Strategy::automatic;
        st.backend = et::Backend::opencl;
        st.queue_counts = k ? et::QueueCounts::device : et::QueueCounts::host;
        const et::DeviceScene ds = et::prepare_device_scene(s, st);
        auto r = et::make_renderer(ds);
        EXPECT_EQ(r->queue_counts_on_device(), k == 1);
        for (uint32_t i = 0; i < 6; ++i)
            r->render_sample(i);
        films[k] = r->sums().mean();
    }
    ASSERT_EQ(films[0].size(), films[1].size());
    EXPECT_EQ(0, std::memcmp(films[0].data(), films[1].data(), films[0].size() * sizeof(float)));
}

} // namespace

namespace {

// Deals a pass out on `lanes` threads at once, each taking waves until none is left: every wave
// dealt, in the order dealt per thread.
std::vector<et::WaveDealer::Wave> deal(int paths, int stride, int wave, int lanes) {
    et::WaveDealer dealer(paths, stride, wave, lanes);
    std::vector<std::vector<et::WaveDealer::Wave>> taken(lanes);
    std::vector<std::thread> threads;
    for (int k = 0; k < lanes; ++k)
        threads.emplace_back([&, k] {
            et::WaveDealer::Wave w;
            while (dealer.next(&w))
                taken[k].push_back(w);
        });
    for (auto& t : threads)
        t.join();
    std::vector<et::WaveDealer::Wave> all;
    for (const auto& t : taken)
        all.insert(all.end(), t.begin(), t.end());
    return all;
}

} // namespace

// Every path of a pass (pixel k x stride) is dealt exactly once, in waves no larger than the
// device's; a pass of several waves a lane ends in waves shrunk to a share of what is left (never
// below kTailWave), and a pass of one wave a lane is dealt every lanes-th path, one wave a lane.
TEST(Schedule, TheDealerHandsOutEveryPathOnceAndEndsInShrinkingWaves) {
    const int kTail = et::WaveDealer::kTailWave;
    struct Case {
        int paths, stride, wave, lanes;
    };
    const Case cases[] = {{262144, 1, 32768, 2}, {262144, 1, 32768, 4}, {100003, 1, 32768, 2},
                          {19200, 1, 9600, 2},   {19201, 2, 9601, 2},   {2400, 8, 1024, 2},
                          {5, 1, 3, 2},          {1, 1, 1, 2},          {7000, 1, 7000, 1},
                          {20000, 3, 1024, 3},   {3, 1, 1, 4},          {3000, 1, 1024, 8}};
    for (const Case& c : cases) {
        SCOPED_TRACE(testing::Message() << c.paths << " paths, stride " << c.stride << ", wave "
                                        << c.wave << ", " << c.lanes << " lanes");
        const std::vector<et::WaveDealer::Wave> waves = deal(c.paths, c.stride, c.wave, c.lanes);
        std::vector<int> seen(static_cast<size_t>(c.paths) * c.stride, 0);
        int smallest = c.wave, below_tail = 0;
        for (const auto& w : waves) {
            ASSERT_GE(w.n, 1);
            ASSERT_LE(w.n, c.wave);
            ASSERT_EQ(w.pixel_stride % c.stride, 0);
            for (int i = 0; i < w.n; ++i) {
                const int64_t pixel = w.first_pixel + int64_t(i) * w.pixel_stride;
                ASSERT_LT(pixel, int64_t(seen.size()));
                ASSERT_EQ(pixel % c.stride, 0) << "a pixel the pass does not render";
                ++seen[static_cast<size_t>(pixel)];
            }
            smallest = std::min(smallest, w.n);
            below_tail += w.n < std::min(kTail, c.wave);
        }
        for (size_t p = 0; p < seen.size(); p += c.stride)
            ASSERT_EQ(seen[p], 1) << "path " << p / c.stride;
        const bool interleaved = c.lanes > 1 && c.lanes <= et::WaveDealer::kMostInterleaved &&
                                 c.paths <= c.lanes * c.wave;
        if (interleaved) { // one wave a lane, dealt path by path
            EXPECT_EQ(int(waves.size()), std::min(c.lanes, c.paths));
            for (const auto& w : waves)
                EXPECT_EQ(w.pixel_stride, c.stride * c.lanes);
        } else if (c.lanes > 1) {
            EXPECT_LE(below_tail, 1) << "only the pass's last wave is below kTailWave";
            if (c.paths > c.lanes * c.wave) { // several waves a lane: the tail shrinks
                EXPECT_LT(smallest, c.wave);
            }
        } else { // one lane: whole waves
            EXPECT_EQ(int(waves.size()), (c.paths + c.wave - 1) / c.wave);
        }
    }
}
