// The learning's one-line summary for a person (render/learning_summary.h), from the figures a
// render's stats hold: each way a verdict can go reads as what it is, and a render without a
// learning technique says nothing.
#include "render/learning_summary.h"

#include <gtest/gtest.h>

namespace {

nlohmann::json figures(const std::string& verdict, const std::string& by, const std::string& kept) {
    return {{"verdict", verdict},
            {"verdict_by", by},
            {"verdict_kept", kept},
            {"verdict_fallback", "compensated"},
            {"verdict_screen_share", 0.0125},
            {"verdict_fallback_error", 0.03},
            {"verdict_kept_error", kept == "none" ? 0.0 : 0.01},
            {"verdict_cost", 1.4},
            {"learning_passes", 32},
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
         "learning: kept the learned tables (the shadow rays of its first update found 1.25% of "
         "their light unblocked); 32 learning passes, 0.50 s"},
        {figures("tables", "measure", "tables"),
         "learning: kept the learned tables (measured: `compensated`'s error 3x the learned "
         "tables', against a cost of 1.4x); 32 learning passes, 0.50 s"},
        {with(figures("compensated", "measure", "tables"), "verdict_fallback_error", 0.012),
         "learning: `compensated` after the learning (measured: `compensated`'s error 1.2x the "
         "learned tables', against a cost of 1.4x); 32 learning passes, 0.50 s"},
        {with(with(figures("compensated", "screen", "none"), "learning_passes", 1),
              "verdict_screen_share", 0.977),
         "learning: `compensated` after the learning (the shadow rays of its first update found "
         "97.7% of their light unblocked); 1 learning pass, 0.50 s"},
        {figures("cosine", "screen", "cosine"),
         "learning: `cosine` after the learning (the shadow rays of its first update found 1.25% "
         "of their light unblocked; then measured: `compensated`'s error 3x `cosine`'s, against "
         "a cost of 1.4x); 32 learning passes, 0.50 s"},
        // Not given yet: the render ended first (or --guide-verdict off).
        {figures("none", "none", "none"),
         "learning: the learned tables, no verdict given; 32 learning passes, 0.50 s"},
        {with(figures("none", "screen", "cosine"), "verdict_kept_error", 0.0),
         "learning: `cosine` in the tables' place, no verdict given (the shadow rays of its first "
         "update found 1.25% of their light unblocked); 32 learning passes, 0.50 s"},
    };
    for (const Case& c : cases)
        EXPECT_EQ(et::learning_summary(c.figures), c.said) << c.figures.dump();
}

TEST(LearningSummary, NothingWhereNothingLearned) {
    EXPECT_EQ(et::learning_summary(nlohmann::json()), "");
    EXPECT_EQ(et::learning_summary(nlohmann::json::object()), "");
}

} // namespace
