// The wavefront schedule (host/lib/render/schedule.h): a pass over every pixel, and a measuring
// pass over every pixel_stride-th pixel only -- the same paths, bit for bit, where it renders, and
// nothing anywhere else, whatever the waves' size.
#include "render/executor_cl.h"
#include "render/executor_cpu.h"
#include "render/film.h"
#include "render/schedule.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <cstring>

namespace {

et::DeviceScene strided_scene() {
    const et::Scene s = ett::ground_under_uneven_sky(13, 7);
    et::RenderSettings st = s.settings;
    st.max_depth = 3;
    st.strategy = et::Strategy::compensated;
    return et::prepare_device_scene(s, st);
}

// One pass of sample 3 with the given stride into a fresh film, in waves of `wave` paths, on the
// native back end (or on OpenCL's first platform, the film handed back).
et::Film strided_pass(const et::DeviceScene& ds, int stride, int wave, bool opencl = false) {
    et::Film film(ds.params.width, ds.params.height);
    std::unique_ptr<et::WavefrontDevice> d;
    if (opencl)
        d = std::make_unique<et::ClDevice>(std::make_unique<et::ClRuntime>(0), ds, wave);
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

} // namespace
