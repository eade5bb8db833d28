// Typed settings (host/lib/load/render_settings.h): every name parses to its value and back,
// the values are the kernels' codes (a strategy is a name alone: prepare/technique.h resolves it
// into the kernels' switches), an unknown name is an error that names the choices, and a retired
// name is an error that says so.
#include "load/render_settings.h"
#include "util/error.h"

#include <gtest/gtest.h>

namespace {

TEST(RenderSettings, NamesRoundTrip) {
    for (const auto& n : et::strategy_names())
        EXPECT_EQ(et::name_of(et::parse_strategy(n, "t")), n);
    for (const auto& n : et::heuristic_names())
        EXPECT_EQ(et::name_of(et::parse_heuristic(n, "t")), n);
    for (const auto& n : et::sampler_names())
        EXPECT_EQ(et::name_of(et::parse_sampler(n, "t")), n);
    for (const auto& n : et::backend_names())
        EXPECT_EQ(et::name_of(et::parse_backend(n, "t")), n);
    for (const auto& n : et::bsdf_sampling_names())
        EXPECT_EQ(et::name_of(et::parse_bsdf_sampling(n, "t")), n);
    EXPECT_EQ(et::strategy_names().size(), 9u); // "lights" is chosen by --lights only
}

TEST(RenderSettings, ValuesAreTheKernelCodes) {
    // Strategies have no kernel code: each name parses to its own value and back.
    EXPECT_EQ(et::parse_strategy("mis", "t"), et::Strategy::mis);
    EXPECT_STREQ(et::name_of(et::Strategy::mis), "mis");
    EXPECT_EQ(et::parse_strategy("sis", "t"), et::Strategy::sis);
    EXPECT_STREQ(et::name_of(et::Strategy::sis), "sis");
    EXPECT_STREQ(et::name_of(et::Strategy::lights), "lights");
    EXPECT_EQ(et::parse_strategy("compensated", "t"), et::Strategy::compensated);
    EXPECT_STREQ(et::name_of(et::Strategy::compensated), "compensated");
    EXPECT_EQ(et::parse_strategy("visibility", "t"), et::Strategy::visibility);
    EXPECT_STREQ(et::name_of(et::Strategy::visibility), "visibility");
    EXPECT_EQ(et::parse_strategy("cosine", "t"), et::Strategy::cosine);
    EXPECT_STREQ(et::name_of(et::Strategy::cosine), "cosine");
    // auto: visible normals for the strategies beyond the paper, the paper's sampling for mis.
    et::RenderSettings st;
    st.strategy = et::Strategy::mis;
    EXPECT_EQ(et::resolved_bsdf_sampling(st), et::BsdfSampling::ndf);
    for (et::Strategy s :
         {et::Strategy::compensated, et::Strategy::visibility, et::Strategy::cosine,
          et::Strategy::automatic}) {
        st.strategy = s;
        EXPECT_EQ(et::resolved_bsdf_sampling(st), et::BsdfSampling::vndf) << et::name_of(s);
    }
    EXPECT_EQ(static_cast<int>(et::parse_bsdf_sampling("vndf", "t")), ETK_GGX_VNDF);
    EXPECT_EQ(static_cast<int>(et::parse_bsdf_sampling("ndf", "t")), ETK_GGX_NDF);
    st.strategy = et::Strategy::compensated;
    st.bsdf_sampling = et::BsdfSampling::ndf;
    EXPECT_EQ(et::resolved_bsdf_sampling(st), et::BsdfSampling::ndf);
    EXPECT_EQ(static_cast<int>(et::parse_sampler("sobol", "t")), ETK_SAMPLER_SOBOL);
    EXPECT_EQ(static_cast<int>(et::parse_heuristic("power", "t")), ETK_HEURISTIC_POWER);
    EXPECT_EQ(static_cast<int>(et::parse_heuristic("balance", "t")), ETK_HEURISTIC_BALANCE);
}

TEST(RenderSettings, AutomaticHeuristicIsPowerForThePapersEstimatorAlone) {
    // The paper's estimator (mis) keeps the power heuristic; the strategies beyond it weigh by
    // the balance heuristic; a heuristic given is kept for every strategy.
    et::RenderSettings st;
    EXPECT_EQ(st.heuristic, et::MisHeuristic::automatic);
    for (const auto& n : et::strategy_names()) {
        st.strategy = et::parse_strategy(n, "t");
        const bool balance =
            n == "compensated" || n == "visibility" || n == "cosine" || n == "auto";
        EXPECT_EQ(et::resolved_heuristic(st),
                  balance ? et::MisHeuristic::balance : et::MisHeuristic::power)
            << n;
    }
    st.heuristic = et::MisHeuristic::power;
    EXPECT_EQ(et::resolved_heuristic(st), et::MisHeuristic::power);
    st.strategy = et::Strategy::mis;
    st.heuristic = et::MisHeuristic::balance;
    EXPECT_EQ(et::resolved_heuristic(st), et::MisHeuristic::balance);
}

// The retired choices (docs/history) are refused by a message that says they were retired, not
// taken for unknown names.
TEST(RenderSettings, RetiredNamesAreRefused) {
    try {
        et::parse_strategy("adaptive", "t");
        FAIL() << "strategy 'adaptive' accepted";
    } catch (const et::Error& e) {
        EXPECT_NE(std::string(e.what()).find("retired"), std::string::npos) << e.what();
    }
    try {
        et::parse_bsdf_sampling("mix", "t");
        FAIL() << "BSDF sampling 'mix' accepted";
    } catch (const et::Error& e) {
        EXPECT_NE(std::string(e.what()).find("retired"), std::string::npos) << e.what();
    }
    for (const auto& n : et::strategy_names())
        EXPECT_NE(n, "adaptive");
    for (const auto& n : et::bsdf_sampling_names())
        EXPECT_NE(n, "mix");
}

// The default estimator goes beyond the paper's (docs/estimators.md): the learned visibility
// tables where they beat MIS compensation, with visible-normal GGX sampling and the balance
// heuristic.
TEST(RenderSettings, DefaultIsAuto) {
    const et::RenderSettings st;
    EXPECT_EQ(st.strategy, et::Strategy::automatic);
    EXPECT_STREQ(et::name_of(st.strategy), "auto");
    EXPECT_EQ(et::resolved_bsdf_sampling(st), et::BsdfSampling::vndf);
    EXPECT_EQ(et::resolved_heuristic(st), et::MisHeuristic::balance);
}

// Without a depth a scene renders glass and inter-reflections (12, Cycles' default), and Russian
// roulette, from rr_depth on, ends most paths long before that.
TEST(RenderSettings, DefaultDepthIsAPathTracersWithRoulette) {
    const et::RenderSettings st;
    EXPECT_EQ(st.max_depth, 12);
    EXPECT_LT(st.rr_depth, st.max_depth);
}

TEST(RenderSettings, SplitCounts) {
    for (int n : {1, 2, 4, 64})
        EXPECT_EQ(et::check_split_count(n, "t"), n);
    for (int bad : {0, -4, 3, 6, 128}) {
        try {
            et::check_split_count(bad, "command line: --light-samples");
            ADD_FAILURE() << "accepted " << bad;
        } catch (const et::Error& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find("--light-samples: must be a power of two"), std::string::npos) << m;
        }
    }
    // Splitting applies to mis; any other strategy with counts other than 1 is an error that
    // names both.
    et::RenderSettings st;
    st.light_samples = 4;
    EXPECT_THROW(et::check_split(st), et::Error)
        << "the default strategy took a split";
    st.strategy = et::Strategy::mis;
    et::check_split(st);
    st.strategy = et::Strategy::compensated;
    try {
        et::check_split(st);
        FAIL() << "no error";
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("(4, 1)"), std::string::npos) << m;
        EXPECT_NE(m.find("'compensated'"), std::string::npos) << m;
        EXPECT_NE(m.find("name the strategy mis"), std::string::npos) << m;
    }
    st.light_samples = 1;
    et::check_split(st);
}

TEST(RenderSettings, UnknownNamesAreClearErrors) {
    try {
        et::parse_strategy("lights", "scene.json: render"); // only --lights selects it
        FAIL() << "no error";
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("scene.json: render"), std::string::npos) << m;
        EXPECT_NE(m.find("unknown strategy 'lights'"), std::string::npos) << m;
        EXPECT_NE(m.find("light, bsdf, mis, uniform, sis"), std::string::npos) << m;
    }
    try {
        et::parse_sampler(std::string(10000, 'x'), "w");
        FAIL() << "no error";
    } catch (const et::Error& e) {
        EXPECT_LT(std::string(e.what()).size(), 200u); // quotes an excerpt, not the value
    }
}

} // namespace
