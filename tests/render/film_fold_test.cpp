// The film's sums kept on the device (--film-sums device; a GPU's default, ClDevice::fold_film):
// a render's sums equal the host's bit for bit -- every pass added on the device; a learning
// technique's passes on the host and the rest on the device; the sums read mid-render; a render
// resumed from the host's sums -- and the renderer says where it keeps them.
#include "render/film_sums.h"
#include "render/renderer.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <memory>
#include <set>

namespace {

struct Sums {
    et::FilmSums sums;
    bool on_device = false;
};

// Samples [from, to) of `s` on OpenCL with the sums kept `at`, after resuming `resume` if given;
// sums() read after each sample in `reads` too.
Sums render_sums(const et::Scene& s, et::FilmSumsAt at, int from, int to,
                 const std::set<int>& reads = {}, const et::FilmSums* resume = nullptr) {
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::opencl;
    st.film_sums = at;
    const et::DeviceScene ds = et::prepare_device_scene(s, st);
    auto r = et::make_renderer(ds);
    if (resume)
        r->resume(*resume);
    for (int k = from; k < to; ++k) {
        EXPECT_TRUE(r->render_sample(static_cast<uint32_t>(k)));
        if (reads.count(k)) {
            EXPECT_EQ(r->sums().pixels(), static_cast<size_t>(s.width) * s.height);
        }
    }
    return {r->sums(), r->sums_on_device()};
}

et::Scene lit_ground() {
    et::Scene s = ett::ground_under_uneven_sky(13, 7);
    s.settings.max_depth = 3;
    s.settings.strategy = et::Strategy::mis;
    return s;
}

TEST(FilmFold, TheDevicesSumsAreTheHostsBitForBit) {
    const et::Scene s = lit_ground();
    const Sums host = render_sums(s, et::FilmSumsAt::host, 0, 6);
    const Sums device = render_sums(s, et::FilmSumsAt::device, 0, 6);
    EXPECT_FALSE(host.on_device);
    EXPECT_TRUE(device.on_device);
    EXPECT_EQ(device.sums.data()[0].count, 6u);
    EXPECT_TRUE(host.sums == device.sums);
    // Read between passes (a live preview, a checkpoint, a noise check): the same sums.
    EXPECT_TRUE(render_sums(s, et::FilmSumsAt::device, 0, 6, {0, 1, 4}).sums == host.sums);
    // auto keeps them on the device on a GPU, on the host on a CPU device (the suite's PoCL).
    EXPECT_EQ(render_sums(s, et::FilmSumsAt::automatic, 0, 1).on_device,
              !et::ClRuntime(0).limits().cpu);
}

// Read back in chunks of 65,536 pixels (ClDevice::take_film_sums): a film of two, the second
// partial.
TEST(FilmFold, AFilmOfSeveralChunksReadsBackWhole) {
    et::Scene s = ett::ground_under_uneven_sky(300, 250);
    s.settings.max_depth = 1;
    s.settings.strategy = et::Strategy::mis;
    const Sums device = render_sums(s, et::FilmSumsAt::device, 0, 2);
    EXPECT_TRUE(device.sums == render_sums(s, et::FilmSumsAt::host, 0, 2).sums);
    EXPECT_EQ(device.sums.data()[device.sums.pixels() - 1].count, 2u);
}

TEST(FilmFold, AResumedRenderAddsToTheHostsSums) {
    const et::Scene s = lit_ground();
    const Sums first = render_sums(s, et::FilmSumsAt::host, 0, 3);
    const Sums all = render_sums(s, et::FilmSumsAt::host, 0, 7);
    const Sums resumed = render_sums(s, et::FilmSumsAt::device, 3, 7, {4}, &first.sums);
    EXPECT_TRUE(resumed.sums == all.sums);
}

// A learning technique's passes: those its policy reads (the verdict's) are read back and folded
// on the device, the others only folded there; the passes after them too: the host's sums.
TEST(FilmFold, ALearningRenderHasTheHostsSums) {
    et::Scene s = ett::side_lit_room(12, 9);
    s.settings.max_depth = 2;
    s.settings.strategy = et::Strategy::visibility;
    const int spp = 72; // 64 learning passes on a film this small, then 8 more
    const Sums host = render_sums(s, et::FilmSumsAt::host, 0, spp);
    const Sums device = render_sums(s, et::FilmSumsAt::device, 0, spp, {spp / 2});
    EXPECT_TRUE(device.on_device);
    EXPECT_EQ(device.sums.data()[0].count, static_cast<uint32_t>(spp));
    EXPECT_TRUE(host.sums == device.sums);
}

// MPI ranks hold each round's sample until every rank's is whole: held passes, kept or dropped,
// are added on the host, the others on the device, and the sums are those of the kept samples.
// A stop request that abandons a pass adds nothing of it.
TEST(FilmFold, HeldAndAbandonedPassesAddAsOnTheHost) {
    const et::Scene s = lit_ground();
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::opencl;
    st.film_sums = et::FilmSumsAt::device;
    const et::DeviceScene ds = et::prepare_device_scene(s, st);
    auto r = et::make_renderer(ds);
    r->set_hold(true);
    EXPECT_FALSE(r->sums_on_device()); // held passes: the host's
    ASSERT_TRUE(r->render_sample(0));
    r->keep_held();
    ASSERT_TRUE(r->render_sample(1));
    r->drop_held();
    ASSERT_TRUE(r->render_sample(1));
    r->keep_held();
    r->set_hold(false);
    EXPECT_TRUE(r->sums_on_device());
    ASSERT_TRUE(r->render_sample(2));
    ASSERT_TRUE(r->render_sample(3));
    int asked = 0;
    r->set_stop([&asked] { return ++asked > 2; }); // mid-pass
    EXPECT_FALSE(r->render_sample(4));
    EXPECT_TRUE(r->abandoned());
    const Sums host = render_sums(s, et::FilmSumsAt::host, 0, 4);
    EXPECT_EQ(r->sums().data()[0].count, 4u);
    EXPECT_TRUE(r->sums() == host.sums);
}

// With AOVs the host keeps the sums (the AOVs' own are added there), whatever was asked.
TEST(FilmFold, ARenderWithAovsKeepsItsSumsOnTheHost) {
    et::Scene s = lit_ground();
    s.settings.aovs = true;
    EXPECT_FALSE(render_sums(s, et::FilmSumsAt::device, 0, 1).on_device);
}

} // namespace
