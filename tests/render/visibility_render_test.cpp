// The visibility strategy inside the renderer (host/lib/render/renderer.cpp,
// visibility_cache.h): its tables depend on the seed alone, so the image is the same bits on any
// thread count (the continuation guide's too), and a render that starts past the learning passes (a
// resume, a farm task, an MPI rank) re-learns the same tables and continues exactly where the
// uninterrupted render was. Its verdict (render/guide_verdict.h) keeps the tables in a room lit
// through an opening; under an open sky it renders the paper's MIS from then on, bit for bit.
#include "render/executor_cpu.h"
#include "render/learning_summary.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <memory>

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
    int verdict = -1;
};

// Samples [from, to) on `threads` threads, resuming `resume` if given.
Result render(const et::Scene& s, int threads, int from, int to,
              const et::FilmSums* resume = nullptr) {
    const ett::SampleRun run = ett::render_samples(s, threads, from, to, resume);
    const et::RenderStats& st = run.renderer->stats();
    return {run.renderer->sums().mean(), ett::learning_count(st, "records"),
            ett::learning_count(st, "continuation_records"), ett::learning_verdict(st)};
}

TEST(VisibilityRender, SameBitsOnAnyThreadCountAndWhenResumed) {
    const et::Scene s = room();
    const int spp = 70; // past the 64 learning passes (the verdict's are 16 .. 23)
    const Result one = render(s, 1, 0, spp), two = render(s, 2, 0, spp);
    EXPECT_GT(one.records, 0u) << "nothing was learned: the test would not see the tables";
    EXPECT_EQ(one.records, two.records);
    // Depth 2: the first bounce's diffuse vertices record (and guide) their continuations.
    EXPECT_GT(one.continuation_records, 0u) << "the continuation guide learned nothing";
    EXPECT_EQ(one.continuation_records, two.continuation_records);
    EXPECT_NE(one.verdict, -1) << "no verdict: the test would not see it";
    EXPECT_EQ(one.verdict, two.verdict);
    EXPECT_TRUE(one.mean == two.mean) << "the image depends on the thread count";
    // The first samples, then a new renderer resumes their film: it renders the learning passes
    // and the verdict's on a scratch film (recording the same outcomes, measuring the same
    // errors), and the rest is the same -- resumed while learning, inside the verdict's passes
    // and past them.
    for (int at : {7, 20, 30, 68}) {
        const et::FilmSums part = ett::render_samples(s, 2, 0, at).renderer->sums();
        const Result resumed = render(s, 2, at, spp, &part);
        EXPECT_EQ(resumed.verdict, one.verdict) << "resumed at " << at;
        EXPECT_TRUE(one.mean == resumed.mean)
            << "a render resumed at " << at << " differs from the uninterrupted one";
    }
}

// A render that says how many samples it takes stops learning at the update after which no
// sample reaches the next one (passes 33-64 of a 64-sample render recorded for tables after pass
// 64): the same film bits, and a render resumed to more samples agrees with one rendered whole;
// one sample past the next update keeps it. A time limit's estimate at least 4x the passes
// learnt takes the learning on, an update at a time, with the same tables up to there; a fixed
// count never does.
TEST(VisibilityRender, LearningEndsWhereNoPlannedSampleUsesTheNextTables) {
    et::Scene s = room();
    s.settings.guide_verdict = false; // (a verdict for MIS would end the learning at its passes)
    auto passes = [](const ett::SampleRun& run) {
        return ett::learning_count(run.renderer->stats(), "learning_passes");
    };
    auto fixed = [](int64_t n) { return et::LearningPlan{n, true}; };
    const ett::SampleRun unplanned = ett::render_samples(s, 2, 0, 40);
    ASSERT_EQ(passes(unplanned), 64u) << "the film's learning passes changed: adjust the plans";
    for (int64_t plan : {40, 64}) {
        const ett::SampleRun planned = ett::render_samples(s, 2, 0, 40, nullptr, fixed(plan));
        EXPECT_EQ(passes(planned), 32u) << "plan " << plan;
        EXPECT_TRUE(planned.renderer->sums().mean() == unplanned.renderer->sums().mean())
            << "plan " << plan << ": a sample's tables changed";
    }
    EXPECT_EQ(passes(ett::render_samples(s, 2, 0, 40, nullptr, fixed(65))), 64u);
    EXPECT_EQ(passes(ett::render_samples(s, 2, 0, 40, nullptr, fixed(1000))), 64u);
    EXPECT_EQ(passes(ett::render_samples(s, 2, 0, 40, nullptr, {255, false})), 64u);
    const ett::SampleRun longer = ett::render_samples(s, 2, 0, 128, nullptr, {256, false});
    EXPECT_EQ(passes(longer), 128u);
    EXPECT_TRUE(longer.renderer->sums().mean() ==
                ett::render_samples(s, 2, 0, 128).renderer->sums().mean())
        << "the samples before the longer learning's first new tables changed";
    // The first 20 of a 24-sample render (learning 16 passes), resumed to 40 (learning 32): the
    // 40-sample render's bits.
    const et::FilmSums part = ett::render_samples(s, 2, 0, 20, nullptr, fixed(24)).renderer->sums();
    EXPECT_TRUE(ett::render_samples(s, 2, 20, 40, &part, fixed(40)).renderer->sums().mean() ==
                unplanned.renderer->sums().mean());
}

// Samples [from, to) of `s` under `strategy`, natively.
std::vector<float> samples(et::Scene s, et::Strategy strategy, int from, int to,
                           int* verdict = nullptr) {
    s.settings.strategy = strategy;
    const ett::SampleRun run = ett::render_samples(s, 2, from, to);
    if (verdict)
        *verdict = ett::learning_verdict(run.renderer->stats());
    return run.renderer->sums().mean();
}

TEST(VisibilityRender, VerdictKeepsTheTablesInARoomLitThroughAnOpening) {
    // The room at depth 1, its walls lit only through the opening: MIS's map samples go
    // everywhere, the tables' towards the opening.
    et::Scene s = room();
    s.width = 64; // enough paths for 16 passes to teach the tables (the verdict's start)
    s.height = 48;
    s.settings.max_depth = 1;
    int verdict = -1;
    const std::vector<float> vis = samples(s, et::Strategy::visibility, 72, 76, &verdict);
    EXPECT_EQ(verdict, 1) << "the tables did not stay where they pay";
    s.settings.heuristic = et::MisHeuristic::balance;
    EXPECT_FALSE(vis == samples(s, et::Strategy::mis, 72, 76)) << "the tables rendered MIS";
}

// A diffuse floor under a constant sky, seen from above: nothing blocks the map, the tables
// learn the map itself and cost more for nothing.
et::Scene open_floor(int width, int height) {
    et::Scene s = ett::base_scene(width, height,
                                  et::make_envmap("sky", ett::constant_image(32, 16, 1.0f), {}));
    s.materials.push_back(ett::diffuse(0.5f));
    ett::add_square(s.triangles, glm::vec3(0, 0, 0), glm::vec3(0, 1, 0), 4.0f, 0);
    s.camera.eye = {0.0f, 3.0f, 0.1f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.fov_deg = 60.0f;
    s.settings.backend = et::Backend::cpu;
    s.settings.max_depth = 1;
    s.settings.seed = 3;
    return s;
}

// The side-lit room with its open side walled but for a window of a sixteenth of it (the
// wall in squares of 0.5, one left out): the shadow rays find little of the map's light.
et::Scene window_room(int width, int height) {
    et::Scene s = room();
    s.width = width;
    s.height = height;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (!(i == 1 && j == 2))
                ett::add_square(s.triangles, glm::vec3(-0.75f + 0.5f * i, 0.25f + 0.5f * j, -1.0f),
                                glm::vec3(0, 0, 1), 0.25f, 0);
    s.camera.eye = {0.0f, 1.0f, -0.5f}; // facing the back wall, the window behind
    s.camera.target = {0.0f, 0.8f, 1.0f};
    return s;
}

// The sample_lights stage draws the learned light samples in batches (kernels/portal_guide.h,
// etk_guide_light_batch): in the window room most cells send a share of them towards the learned
// portal table, so batches mix the portal's samples with the tables', before the first tables,
// while learning and after. The same bits as the shade stage drawing each, on both back ends.
TEST(VisibilityRender, BatchedLearnedLightSamplesGiveTheSameBits) {
    et::Scene s = window_room(24, 16);
    s.settings.max_depth = 3;
    s.settings.guide_verdict = false; // the tables on every pass after the learning
    for (et::Backend b : {et::Backend::cpu, et::Backend::opencl}) {
        SCOPED_TRACE(b == et::Backend::cpu ? "native" : "OpenCL");
        s.settings.backend = b;
        std::vector<float> films[2];
        for (int m = 0; m < 2; ++m) {
            s.settings.light_batch = m ? et::LightBatch::on : et::LightBatch::off;
            const ett::SampleRun run = ett::render_samples(s, 2, 0, 70);
            EXPECT_EQ(run.renderer->batches_light_samples(), m == 1);
            EXPECT_GT(ett::learning_count(run.renderer->stats(), "cells_with_portal_share"), 0u)
                << "no cell draws from the portal table: the test would not see that part";
            films[m] = run.renderer->sums().mean();
        }
        EXPECT_GT(ett::image_mean(films[0]), 0.0);
        EXPECT_TRUE(films[0] == films[1]) << "batched, the learned light samples differ";
    }
}

TEST(VisibilityRender, VerdictForMisRendersThePapersEstimatorFromThenOn) {
    // MIS wins the verdict on the open floor; the passes after it are MIS's own (the strategy's
    // balance heuristic), bit for bit, batched map samples and all.
    et::Scene s = open_floor(32, 24);
    int verdict = -1;
    const std::vector<float> vis = samples(s, et::Strategy::visibility, 72, 80, &verdict);
    EXPECT_EQ(verdict, 0) << "the tables stayed under an open sky";
    // The verdict ends the learning: a render resumed inside its passes or past them (which
    // renders them first) continues exactly where the uninterrupted one was.
    const std::vector<float> whole = samples(s, et::Strategy::visibility, 0, 40);
    s.settings.strategy = et::Strategy::visibility;
    const uint64_t learned = render(s, 2, 0, 24).records; // through the verdict's passes
    EXPECT_GT(learned, render(s, 2, 0, 16).records) << "the verdict's passes did not learn";
    EXPECT_EQ(render(s, 2, 0, 40).records, learned) << "the learning went on past the verdict";
    // and its figures say so: 24 passes learnt (16, then the verdict's 8), not the film's 64.
    EXPECT_EQ(
        ett::learning_count(ett::render_samples(s, 2, 0, 40).renderer->stats(), "learning_passes"),
        24u);
    for (int at : {20, 30}) {
        s.settings.strategy = et::Strategy::visibility;
        const et::FilmSums part = ett::render_samples(s, 2, 0, at).renderer->sums();
        const Result resumed = render(s, 2, at, 40, &part);
        EXPECT_EQ(resumed.verdict, 0) << "resumed at " << at;
        EXPECT_TRUE(whole == resumed.mean) << "resumed at " << at << ": not the same image";
    }
    s.settings.heuristic = et::MisHeuristic::balance;
    EXPECT_TRUE(vis == samples(s, et::Strategy::mis, 72, 80))
        << "the passes after a verdict for MIS are not MIS's";
    // Without the verdict the tables render them.
    s.settings.guide_verdict = false;
    s.settings.heuristic = et::MisHeuristic::automatic;
    EXPECT_FALSE(samples(s, et::Strategy::visibility, 72, 80, &verdict) == vis);
    EXPECT_EQ(verdict, -1);
}

// auto's screen: on the open floor at depth 2 its first passes' shadow rays find all the light
// they carry, so the verdict is compensated's at the first update with records enough, without
// measuring; the passes after it are compensated's, bit for bit, and a render resumed past it
// continues exactly. In the side-lit room, whose rays find little of the light, the verdict is
// measured. (At depth 1: the next test.)
TEST(VisibilityRender, AutoScreensOutASceneThatBlocksNoLight) {
    et::Scene s = open_floor(96, 64); // 6,144 paths a pass: the screen's records in two
    s.settings.strategy = et::Strategy::automatic;
    s.settings.max_depth = 2;
    const ett::SampleRun run = ett::render_samples(s, 2, 0, 12);
    const et::RenderStats& st = run.renderer->stats();
    EXPECT_EQ(ett::learning_verdict(st), 0);
    EXPECT_EQ(ett::learning_verdict_by(st), "screen");
    EXPECT_EQ(ett::learning_count(st, "learning_passes"), 2u) << "not where the records sufficed";
    EXPECT_GT(st.learning["verdict_screen_share"].get<double>(), 0.999);
    const std::vector<float> whole = run.renderer->sums().mean();
    const std::vector<float> after = samples(s, et::Strategy::automatic, 4, 12);
    EXPECT_TRUE(after == samples(s, et::Strategy::compensated, 4, 12))
        << "the passes after the screen are not compensated's";
    const et::FilmSums part = ett::render_samples(s, 2, 0, 3).renderer->sums();
    s.settings.strategy = et::Strategy::automatic;
    EXPECT_TRUE(render(s, 2, 3, 12, &part).mean == whole) << "resumed past the screen";

    et::Scene r = room();
    r.settings.strategy = et::Strategy::automatic;
    r.width = 96;
    r.height = 64;
    const ett::SampleRun room_run = ett::render_samples(r, 2, 0, 24);
    const et::RenderStats& rs = room_run.renderer->stats();
    EXPECT_EQ(ett::learning_verdict_by(rs), "measure");
    EXPECT_LT(rs.learning["verdict_screen_share"].get<double>(), 0.5);
}

// auto's screen at depth 1: on the open floor, whose first passes' shadow rays find all the light
// they carry, the tables render those two only (the screen's records); the binned light samples
// (the cosine strategy's) render the next ones, bit for bit, and their passes 16 .. 31 are weighed
// against compensated's measuring passes: under the uniform sky, whose light times the cosine the
// floor's one bin holds exactly, they win and render on. A render resumed inside the verdict's
// passes or past them continues exactly.
TEST(VisibilityRender, AutoAtDepthOneScreensTheTablesOutUnderTheOpenSky) {
    et::Scene s = open_floor(96, 64); // 6,144 paths a pass: the screen's records in two
    s.settings.strategy = et::Strategy::automatic;
    const ett::SampleRun run = ett::render_samples(s, 2, 0, 40);
    const et::RenderStats& st = run.renderer->stats();
    EXPECT_EQ(ett::learning_verdict_by(st), "screen");
    EXPECT_EQ(ett::learning_count(st, "learning_passes"), 2u);
    EXPECT_GT(st.learning["verdict_screen_share"].get<double>(), 0.999);
    EXPECT_EQ(st.learning["verdict_kept"].get<std::string>(), "cosine");
    EXPECT_EQ(st.learning["verdict"].get<std::string>(), "cosine");
    EXPECT_LT(st.learning["verdict_kept_error"].get<double>(),
              st.learning["verdict_fallback_error"].get<double>());
    EXPECT_GT(st.learning["verdict_fallback_error"].get<double>(), 0.0) << "nothing measured";
    const std::string said = et::learning_summary(st.learning);
    EXPECT_EQ(said.rfind("learning: `cosine` after the learning (its shadow rays had found ", 0),
              0u)
        << said;
    EXPECT_NE(said.find("% of their light unblocked at the screen; then measured: "
                        "`compensated`'s error "),
              std::string::npos)
        << said;
    EXPECT_NE(said.find("; 2 learning passes and the verdict's: "), std::string::npos) << said;
    EXPECT_TRUE(samples(s, et::Strategy::automatic, 2, 40) ==
                samples(s, et::Strategy::cosine, 2, 40))
        << "the passes after the screen are not the cosine strategy's";
    for (int at : {20, 36}) {
        const et::FilmSums part = ett::render_samples(s, 2, 0, at).renderer->sums();
        s.settings.strategy = et::Strategy::automatic;
        EXPECT_TRUE(render(s, 2, at, 40, &part).mean == run.renderer->sums().mean())
            << "resumed at " << at;
    }
}

// auto's screen where the shadow rays find little of the light they carry unblocked (the
// window room): the tables at once, at depth 1 and past it, without the verdict's measuring
// passes: the same bits as the tables without a verdict (the screen's update uploads its tables
// as any other); a render resumed past the screen continues exactly.
TEST(VisibilityRender, AutoKeepsTheTablesAtOnceWhereLittleLightComesThrough) {
    et::Scene s = window_room(96, 64);
    s.settings.strategy = et::Strategy::automatic;
    for (int depth : {1, 2}) {
        s.settings.max_depth = depth;
        const ett::SampleRun run = ett::render_samples(s, 2, 0, 24);
        const et::RenderStats& st = run.renderer->stats();
        EXPECT_EQ(ett::learning_verdict(st), 1) << "depth " << depth;
        EXPECT_EQ(ett::learning_verdict_by(st), "screen") << "depth " << depth;
        const double share = st.learning["verdict_screen_share"].get<double>();
        EXPECT_GT(share, 0.0);
        EXPECT_LT(share, 0.1);
        EXPECT_EQ(st.learning["verdict_fallback_error"].get<double>(), 0.0) << "measured";
        EXPECT_EQ(st.learning["verdict_kept"].get<std::string>(), "none");
        const std::string said = et::learning_summary(st.learning);
        EXPECT_EQ(said.rfind("learning: kept the learned tables (its shadow rays had found ", 0),
                  0u)
            << said;
        EXPECT_EQ(said.find("measured"), std::string::npos) << said;
        et::Scene unjudged = s;
        unjudged.settings.guide_verdict = false;
        EXPECT_TRUE(render(unjudged, 2, 0, 24).mean == run.renderer->sums().mean())
            << "not the tables' bits, depth " << depth;
        const et::FilmSums part = ett::render_samples(s, 2, 0, 10).renderer->sums();
        EXPECT_TRUE(render(s, 2, 10, 24, &part).mean == run.renderer->sums().mean())
            << "resumed past the screen, depth " << depth;
    }
}

// Where the screen does not put the binned samples in the tables' place at depth 1, the tables
// are weighed against compensated alone: on the open floor at 32 x 24 (768 paths a pass, too few
// records before the verdict's passes for the screen), and in the side-lit room, whose first
// pass's shadow rays find little of their light. Past depth 1 the binned samples never serve.
TEST(VisibilityRender, AutoAtDepthOneWeighsTheTablesWhereTheScreenSeesNoOpenSky) {
    et::Scene s = open_floor(32, 24);
    s.settings.strategy = et::Strategy::automatic;
    const et::RenderStats st = ett::render_samples(s, 2, 0, 24).renderer->stats();
    EXPECT_EQ(st.learning["verdict_screen_share"].get<double>(), -1.0) << "screened";
    EXPECT_EQ(st.learning["verdict_kept"].get<std::string>(), "tables");
    EXPECT_EQ(ett::learning_verdict_by(st), "measure");

    et::Scene r = room();
    r.settings.strategy = et::Strategy::automatic;
    r.settings.max_depth = 1;
    r.width = 96; // 768 pixels measured (every 8th)
    r.height = 64;
    const et::RenderStats rs = ett::render_samples(r, 2, 0, 24).renderer->stats();
    EXPECT_LT(rs.learning["verdict_screen_share"].get<double>(), 0.5);
    EXPECT_GE(rs.learning["verdict_screen_share"].get<double>(), 0.1) << "the tables at once";
    EXPECT_EQ(ett::learning_verdict_by(rs), "measure");
    EXPECT_EQ(rs.learning["verdict_kept"].get<std::string>(), "tables");
    EXPECT_EQ(rs.learning["verdict"].get<std::string>(), "tables");
    r.settings.max_depth = 2;
    const et::RenderStats deep = ett::render_samples(r, 2, 0, 24).renderer->stats();
    EXPECT_EQ(ett::learning_verdict_by(deep), "measure");
    EXPECT_EQ(deep.learning["verdict_kept"].get<std::string>(), "tables");
}

} // namespace
