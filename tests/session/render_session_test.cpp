// The render session as a front end other than the command line drives it: run to the settings'
// spp, stopped on request from a progress callback after whole rounds, resumed from its state to
// the film of an unbroken run bit for bit; its report is one list written as JSON and metadata.
#include "single_cluster.h"
#include "render_util.h"
#include "session/render_report.h"
#include "session/render_session.h"

#include <gtest/gtest.h>

#include <csignal>
#include <map>

namespace {

std::unique_ptr<et::PreparedRender> prepared_room(int spp) {
    et::Scene s = ett::side_lit_room(8, 6);
    s.settings.backend = et::Backend::cpu;
    s.settings.threads = 2;
    s.settings.spp = spp;
    s.settings.max_depth = 3;
    s.settings.strategy = et::Strategy::mis;
    const et::RenderSettings st = s.settings;
    return et::prepare_render(std::move(s), st);
}

TEST(RenderSession, StopsOnRequestAndResumesBitIdentical) {
    const auto p = prepared_room(12);
    et::RenderSession whole(ett::single_cluster(), *p, {});
    whole.start();
    const et::SessionResult all = whole.run();
    EXPECT_EQ(all.spp, 12);
    EXPECT_EQ(all.signal, 0);
    EXPECT_FALSE(all.stopped);

    et::RenderSession first(ett::single_cluster(), *p, {});
    first.start();
    et::SessionCallbacks cb;
    int calls = 0;
    cb.progress = [&](int done, double) {
        ++calls;
        if (done == 5)
            first.request_stop(SIGINT);
    };
    const et::SessionResult part = first.run(cb);
    EXPECT_EQ(part.spp, 5);
    EXPECT_EQ(calls, 5);
    EXPECT_EQ(part.signal, SIGINT);
    EXPECT_FALSE(part.sums == all.sums);

    et::SessionOptions resume;
    resume.resume = true;
    et::RenderSession rest(ett::single_cluster(), *p, resume);
    rest.resume(first.state_of(part.sums));
    rest.start();
    EXPECT_EQ(rest.resumed_from(), 5);
    const et::SessionResult resumed = rest.run();
    EXPECT_EQ(resumed.spp, 12);
    EXPECT_EQ(resumed.resumed_from, 5);
    EXPECT_TRUE(resumed.sums == all.sums) << "the resumed film differs from the unbroken one";
}

// The session tells a learning technique the render's samples: a 40-sample render of the
// visibility strategy learns from 32 passes (the tables after pass 64 would serve no sample).
TEST(RenderSession, LearningTechniqueLearnsOnlyForSamplesTheRenderTakes) {
    et::Scene s = ett::side_lit_room(24, 16);
    s.settings.backend = et::Backend::cpu;
    s.settings.threads = 2;
    s.settings.spp = 40;
    s.settings.max_depth = 2;
    s.settings.strategy = et::Strategy::visibility;
    s.settings.guide_verdict = false;
    const et::RenderSettings st = s.settings;
    const auto p = et::prepare_render(std::move(s), st);
    et::RenderSession session(ett::single_cluster(), *p, {});
    session.start();
    const et::SessionResult r = session.run();
    EXPECT_EQ(r.spp, 40);
    EXPECT_EQ(ett::learning_count(r.stats, "learning_passes"), 32u);
}

// Every fact with a place in both outputs says the same in both; facts of one output only stay
// out of the other.
TEST(RenderReport, StatsAndMetadataFromOneList) {
    const auto p = prepared_room(3);
    et::RenderSession s(ett::single_cluster(), *p, {});
    s.start();
    const et::SessionResult r = s.run();
    const et::ProgramBuildInfo build;
    const et::RenderReport report = et::render_report({s, r, build, 1});
    const nlohmann::json j = et::report_json(report);
    std::map<std::string, std::string> meta;
    for (const auto& [key, value] : et::report_metadata(report))
        meta[key] = value;
    EXPECT_EQ(j["spp"], 3);
    EXPECT_EQ(meta["envtrace:spp"], "3");
    EXPECT_EQ(j["strategy"], "mis");
    EXPECT_EQ(meta["envtrace:strategy"], "mis");
    EXPECT_EQ(j["interrupted"], "no");
    EXPECT_EQ(meta["envtrace:interrupted"], "no");
    EXPECT_EQ(meta["envtrace:noise_target"], "none");
    EXPECT_FALSE(j.contains("noise_target"));
    EXPECT_FALSE(j.contains("seed"));
    EXPECT_EQ(meta.count("envtrace:width"), 0u);
    for (const et::ReportFact& f : report) {
        if (f.json.empty() || f.exr.empty() || !f.value.is_primitive())
            continue;
        const nlohmann::json& v = j[nlohmann::json::json_pointer(f.json)];
        EXPECT_EQ(v, f.value) << f.json;
        if (v.is_string()) {
            EXPECT_EQ(meta[f.exr], v.get<std::string>()) << f.exr;
        } else if (v.is_number_integer()) {
            EXPECT_EQ(meta[f.exr], std::to_string(v.get<int64_t>())) << f.exr;
        }
    }
}

} // namespace
