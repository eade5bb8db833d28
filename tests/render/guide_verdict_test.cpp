// The visibility strategy's verdict (host/lib/render/guide_verdict.h) on films made up here:
// it keeps the tables when MIS's measured error pays for their cost and not otherwise, a few
// fireflies do not decide, and passes out of order are refused.
#include "render/guide_verdict.h"
#include "util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace {

constexpr int kW = 64, kH = 64, kPasses = 8;

// A pass's film: per pixel mean 1 plus `amplitude` x a deterministic noise in [-1, 1).
std::vector<float> film(uint32_t seed, double amplitude) {
    std::vector<float> f(4 * kW * kH);
    uint32_t x = seed * 2654435761u + 1u;
    for (int i = 0; i < kW * kH; ++i) {
        x = x * 1664525u + 1013904223u;
        const double u = (x >> 8) * (1.0 / 16777216.0) * 2.0 - 1.0;
        const float v = static_cast<float>(1.0 + amplitude * u);
        f[4 * i] = f[4 * i + 1] = f[4 * i + 2] = v;
        f[4 * i + 3] = 1.0f;
    }
    return f;
}

// MIS's passes with noise `mis`, the tables' with `tables` (the same noise, scaled: the errors'
// ratio is (mis / tables)^2 but for the few largest values the 99.9% quantile caps, all of them
// MIS's); `edit` may change a film before it is added.
et::GuideVerdict measure(double mis, double tables, double cost,
                         void (*edit)(int t, int k, std::vector<float>&) = nullptr) {
    et::GuideVerdict v(kW, kH, kPasses, cost);
    for (int k = 0; k < kPasses; ++k)
        for (int t = 1; t >= 0; --t) { // the renderer adds the tables' passes first
            std::vector<float> f = film(static_cast<uint32_t>(k), t ? tables : mis);
            if (edit)
                edit(t, k, f);
            v.add(t, k, f.data());
        }
    return v;
}

TEST(GuideVerdict, TablesStayWhereMisErrsByMoreThanTheirCost) {
    // Errors 1.44 : 1 -- the tables stay at a cost of 1.25, not at 1.5.
    const et::GuideVerdict cheap = measure(0.12, 0.1, 1.25), dear = measure(0.12, 0.1, 1.5);
    EXPECT_NEAR(cheap.fallback_error() / cheap.kept_error(), 1.44, 0.015);
    EXPECT_TRUE(cheap.kept_wins());
    EXPECT_FALSE(dear.kept_wins());
    // Equal errors: MIS, the cheaper, whatever the cost above 1.
    EXPECT_FALSE(measure(0.1, 0.1, 1.01).kept_wins());
    // Far noisier MIS (a room lit through an opening).
    const et::GuideVerdict room = measure(0.5, 0.1, 1.5);
    EXPECT_TRUE(room.kept_wins());
    EXPECT_NEAR(room.fallback_error() / room.kept_error(), 25.0, 0.25);
}

TEST(GuideVerdict, AFireflyDoesNotDecide) {
    // Equal noise, and one pixel of one of MIS's passes 1000x its mean: the tables would win at a
    // cost of 1.25 if that pixel counted in full (it alone would add ~750x a pixel's mean error).
    auto firefly = [](int t, int k, std::vector<float>& f) {
        if (t == 0 && k == 1)
            f[4 * 2000] = f[4 * 2000 + 1] = f[4 * 2000 + 2] = 1000.0f;
    };
    const et::GuideVerdict v = measure(0.1, 0.1, 1.25, firefly);
    EXPECT_LT(v.fallback_error(), 1.05 * v.kept_error());
    EXPECT_FALSE(v.kept_wins());
}

TEST(GuideVerdict, DroppedSamplesAndBlackFilmsAreNoEvidence) {
    // A black image: nothing to compare; MIS, the cheaper.
    et::GuideVerdict black(kW, kH, kPasses, 1.25);
    std::vector<float> zero(4 * kW * kH, 0.0f);
    for (int i = 0; i < kW * kH; ++i)
        zero[4 * i + 3] = 1.0f;
    for (int k = 0; k < kPasses; ++k)
        for (int t = 0; t < 2; ++t)
            black.add(t, k, zero.data());
    EXPECT_FALSE(black.kept_wins());
    EXPECT_EQ(black.fallback_error(), 0.0);
    // A pixel whose samples were all dropped (w = 0) in one block is left out, not read as 0.
    auto drop = [](int t, int k, std::vector<float>& f) {
        if (t == 1 && k < kPasses / 2)
            f[4 * 77] = f[4 * 77 + 1] = f[4 * 77 + 2] = f[4 * 77 + 3] = 0.0f;
    };
    const et::GuideVerdict v = measure(0.12, 0.1, 1.25, drop);
    EXPECT_TRUE(v.kept_wins());
    EXPECT_TRUE(std::isfinite(v.fallback_error()) && std::isfinite(v.kept_error()));
}

// A ratio of errors spread evenly over the pixels is a measurement; the same size of ratio made
// by two pixels of 256 may be chance. Films without noise: each pixel's two blocks are 1 + d and
// 1 - d, so its error is fixed by d. The tables' d is 0.1 everywhere; the fallback's is
// 0.1 sqrt(1.3) everywhere (ratio 1.3, no spread: the tables stay at a cost of 1.25), or 0.1 but
// 0.1 sqrt(65) at two pixels (ratio 1.5, its log's standard error 0.235: the bar is 1.25 x 1.265 =
// 1.58, and the fallback stays, where the ratio alone would have kept the tables).
TEST(GuideVerdict, ARatioFewPixelsMakeMustBeSure) {
    constexpr int w = 16, h = 16;
    auto verdict = [&](bool spread) {
        et::GuideVerdict v(w, h, kPasses, 1.25);
        for (int k = 0; k < kPasses; ++k)
            for (int t = 1; t >= 0; --t) {
                std::vector<float> f(4 * w * h);
                for (int i = 0; i < w * h; ++i) {
                    const double scale = t        ? 1.0
                                         : spread ? std::sqrt(1.3)
                                                  : (i == 37 || i == 200 ? std::sqrt(65.0) : 1.0);
                    const double d = 0.1 * scale * (k < kPasses / 2 ? 1.0 : -1.0);
                    f[4 * i] = f[4 * i + 1] = f[4 * i + 2] = static_cast<float>(1.0 + d);
                    f[4 * i + 3] = 1.0f;
                }
                v.add(t, k, f.data());
            }
        return v;
    };
    const et::GuideVerdict spread = verdict(true), few = verdict(false);
    EXPECT_NEAR(spread.fallback_error() / spread.kept_error(), 1.3, 0.01);
    EXPECT_LT(spread.log_ratio_se(), 0.01);
    EXPECT_TRUE(spread.kept_wins());
    EXPECT_NEAR(few.fallback_error() / few.kept_error(), 1.5, 0.03);
    EXPECT_NEAR(few.log_ratio_se(), 0.235, 0.02);
    EXPECT_FALSE(few.kept_wins());
}

TEST(GuideVerdict, RefusesPassesOutOfOrderAndOddCounts) {
    EXPECT_THROW(et::GuideVerdict(kW, kH, 3, 1.25), et::Error);
    EXPECT_THROW(et::GuideVerdict(kW, kH, 2, 1.25), et::Error);
    EXPECT_THROW(et::GuideVerdict(0, kH, 8, 1.25), et::Error);
    et::GuideVerdict v(kW, kH, kPasses, 1.25);
    const std::vector<float> f = film(1, 0.1);
    v.add(1, 0, f.data());
    EXPECT_THROW(v.add(1, 2, f.data()), et::Error);
    EXPECT_THROW(v.add(2, 0, f.data()), et::Error);
    EXPECT_FALSE(v.kept_wins()) << "a verdict before its passes";
}

} // namespace
