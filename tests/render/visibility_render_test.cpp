// The visibility strategy inside the renderer (host/lib/render/renderer.cpp,
// visibility_cache.h): its tables depend on the seed alone, so the image is the same bits on any
// thread count (the continuation guide's too), and a render that starts past the learning passes (a
// resume, a farm task, an MPI rank) re-learns the same tables and continues exactly where the
// uninterrupted render was.
#include "render_util.h"

#include <gtest/gtest.h>

namespace {

// The side-lit room (render_util.h): the tables move the light samples towards the opening.
et::Scene room() {
    et::Scene s = ett::side_lit_room(24, 16);
    s.settings.strategy = et::Strategy::visibility;
    s.settings.backend = et::Backend::cpu;
    s.settings.max_depth = 2;
    s.settings.seed = 5;
    return s;
}

struct Result {
    std::vector<float> mean;
    uint64_t records = 0, continuation_records = 0;
};

// Samples [from, to) on `threads` threads, resuming `resume` if given.
Result render(const et::Scene& s, int threads, int from, int to,
              const et::FilmSums* resume = nullptr) {
    const ett::SampleRun run = ett::render_samples(s, threads, from, to, resume);
    const et::RenderStats& st = run.renderer->stats();
    return {run.renderer->sums().mean(), st.guide_records, st.guide_continuation_records};
}

TEST(VisibilityRender, SameBitsOnAnyThreadCountAndWhenResumed) {
    const et::Scene s = room();
    const int spp = 70; // past the 64 learning passes
    const Result one = render(s, 1, 0, spp), two = render(s, 2, 0, spp);
    EXPECT_GT(one.records, 0u) << "nothing was learned: the test would not see the tables";
    EXPECT_EQ(one.records, two.records);
    // Depth 2: the first bounce's diffuse vertices record (and guide) their continuations.
    EXPECT_GT(one.continuation_records, 0u) << "the continuation guide learned nothing";
    EXPECT_EQ(one.continuation_records, two.continuation_records);
    EXPECT_TRUE(one.mean == two.mean) << "the image depends on the thread count";
    // The first 7 samples, then a new renderer resumes their film at sample 7: it renders the
    // learning passes on a scratch film (recording the same outcomes), and the rest is the same.
    const et::FilmSums part = ett::render_samples(s, 2, 0, 7).renderer->sums();
    const Result resumed = render(s, 2, 7, spp, &part);
    EXPECT_TRUE(one.mean == resumed.mean) << "a resumed render differs from the uninterrupted one";
}

} // namespace
