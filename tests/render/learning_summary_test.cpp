// The learning's one-line summary for a person (render/learning_summary.h), from the figures a
// render's stats hold: each way a verdict can go reads as what it is, and a render without a
// learning technique says nothing.
#include "render/learning_summary.h"

#include <gtest/gtest.h>

namespace {

nlohmann::json figures(const std::string& verdict, const std::string& by, const std::string& kept) {
    return {{"verdict", verdict},
            {"verdict_by", by},
            {"verdict_measured", verdict != "none" && kept != "none"},
            {"verdict_kept", kept},
            {"verdict_fallback", "compensated"},
            {"verdict_screen_share", 0.0125},
            {"verdict_fallback_error", kept == "none" ? 0.0 : 0.03},
            {"verdict_kept_error", kept == "none" ? 0.0 : 0.01},
            {"verdict_cost", 1.4},
            {"verdict_seconds", kept == "none" ? 0.0 : 0.25},
            {"learning_passes", 32},
            {"learned_passes", 32},
            {"learning_seconds", 0.5}};
}

nlohmann::json with(nlohmann::json j, const std::string& key, const nlohmann::json& value) {
    j[key] = value;
    return j;
}

struct Case {
    nlohmann::json figures;
    std::string said;
};

TEST(LearningSummary, SaysWhatTheVerdictKeptAndWhy) {
    const Case cases[] = {
        {figures("tables", "screen", "none"),
         "learning: kept the learned tables (its shadow rays had found 1.25% of their light "
         "unblocked at the screen); 32 learning passes: 0.50 s"},
        {figures("tables", "measure", "tables"),
         "learning: kept the learned tables (measured: `compensated`'s error 3x the learned "
         "tables', against a cost of 1.4x); 32 learning passes and the verdict's: 0.75 s"},
        {with(figures("compensated", "measure", "tables"), "verdict_fallback_error", 0.012),
         "learning: `compensated` after the learning (measured: `compensated`'s error 1.2x the "
         "learned tables', against a cost of 1.4x); 32 learning passes and the verdict's: 0.75 s"},
        // The visibility strategy's verdict, against the paper's estimator.
        {with(figures("tables", "measure", "tables"), "verdict_fallback", "mis"),
         "learning: kept the learned tables (measured: `mis`'s error 3x the learned tables', "
         "against a cost of 1.4x); 32 learning passes and the verdict's: 0.75 s"},
        {with(figures("tables", "measure", "tables"), "verdict_kept_error", 0.0),
         "learning: kept the learned tables (measured: the learned tables' error 0, "
         "`compensated`'s 0.03, against a cost of 1.4x); 32 learning passes and the verdict's: "
         "0.75 s"},
        {with(with(figures("compensated", "screen", "none"), "learned_passes", 1),
              "verdict_screen_share", 0.977),
         "learning: `compensated` after the learning (its shadow rays had found 97.7% of their "
         "light unblocked at the screen); 1 learning pass: 0.50 s"},
        // The ratio's standard error, where the stats hold it: 1.3x beat a cost of 1.12x, but
        // not by the factor it is uncertain by.
        {with(
             with(with(figures("compensated", "screen", "cosine"), "verdict_fallback_error", 0.013),
                  "verdict_cost", 1.12),
             "verdict_log_ratio_se", 0.23),
         "learning: `compensated` after the learning (its shadow rays had found 1.25% of their "
         "light unblocked at the screen; then measured: `compensated`'s error 1.3x `cosine`'s, "
         "uncertain by a factor of 1.26, against a cost of 1.12x); 32 learning passes and the "
         "verdict's: 0.75 s"},
        {figures("cosine", "screen", "cosine"),
         "learning: `cosine` after the learning (its shadow rays had found 1.25% of their light "
         "unblocked at the screen; then measured: `compensated`'s error 3x `cosine`'s, against a "
         "cost of 1.4x); 32 learning passes and the verdict's: 0.75 s"},
    };
    for (const Case& c : cases)
        EXPECT_EQ(et::learning_summary(c.figures), c.said) << c.figures.dump();
}

// Not given yet: the render ended first (only the passes it learnt count), or the verdict is off.
TEST(LearningSummary, AVerdictNotYetGiven) {
    nlohmann::json ended = figures("none", "none", "tables");
    ended["learned_passes"] = 10;
    ended["verdict_seconds"] = 0.0;
    EXPECT_EQ(et::learning_summary(ended),
              "learning: the learned tables, no verdict given; 10 learning passes: 0.50 s");
    nlohmann::json waiting = figures("none", "screen", "cosine");
    waiting["verdict_seconds"] = 0.0;
    EXPECT_EQ(et::learning_summary(waiting),
              "learning: `cosine` in the tables' place, no verdict given (its shadow rays had "
              "found 1.25% of their light unblocked at the screen); 32 learning passes: 0.50 s");
}

TEST(LearningSummary, NothingWhereNothingLearned) {
    EXPECT_EQ(et::learning_summary(nlohmann::json()), "");
    EXPECT_EQ(et::learning_summary(nlohmann::json::object()), "");
}

} // namespace
