// The shared polynomial trigonometry (kernels/trig.h) against double-precision libm: every
// quadrant of sin/cos(pi x) (the quadrant is picked with bit operations, not selects), the exact
// values at multiples of 1/2, odd and even symmetry, and atan2 in all four quadrants.
#include "kernels/trig.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

TEST(Trig, SinCosPiMatchLibmInEveryQuadrant) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> U(-4.0f, 4.0f);
    for (int i = 0; i < 200000; ++i) {
        const float x = i < 1601 ? -4.0f + i * 0.005f : U(rng); // a grid, then random points
        const etk::float2 sc = etk::etk_sincospi(x);
        const double s = std::sin(M_PI * double(x)), c = std::cos(M_PI * double(x));
        ASSERT_NEAR(sc.x, s, 3e-7) << "x " << x;
        ASSERT_NEAR(sc.y, c, 3e-7) << "x " << x;
    }
}

TEST(Trig, SinCosPiExactAtHalfIntegersAndSymmetric) {
    const float s2 = 0.70710677f;
    struct Case {
        float x, s, c;
    };
    for (Case k : {Case{0.0f, 0.0f, 1.0f}, Case{0.5f, 1.0f, 0.0f}, Case{1.0f, 0.0f, -1.0f},
                   Case{1.5f, -1.0f, 0.0f}, Case{2.0f, 0.0f, 1.0f}, Case{-0.5f, -1.0f, 0.0f},
                   Case{-1.0f, 0.0f, -1.0f}}) {
        const etk::float2 sc = etk::etk_sincospi(k.x);
        EXPECT_EQ(sc.x, k.s) << "x " << k.x;
        EXPECT_EQ(sc.y, k.c) << "x " << k.x;
    }
    EXPECT_NEAR(etk::etk_sincospi(0.25f).x, s2, 1e-7f);
    EXPECT_NEAR(etk::etk_sincospi(0.75f).y, -s2, 1e-7f);
    for (float x : {1e-30f, 0.1f, 0.3f, 0.7f, 1.2f, 1.9f, 3.3f}) {
        const etk::float2 p = etk::etk_sincospi(x), m = etk::etk_sincospi(-x);
        EXPECT_EQ(m.x, -p.x) << "odd sine, x " << x;
        EXPECT_EQ(m.y, p.y) << "even cosine, x " << x;
    }
    // Near a multiple of 1/2 the reduction is exact: small results keep their relative accuracy.
    for (float e : {1e-3f, 1e-5f, 6e-8f}) {
        const float a = 1.0f - e, b = 0.5f - e; // the distances are exact in double
        EXPECT_NEAR(etk::etk_sincospi(a).x / std::sin(M_PI * (1.0 - a)), 1.0, 1e-6) << e;
        EXPECT_NEAR(etk::etk_sincospi(b).y / std::sin(M_PI * (0.5 - b)), 1.0, 1e-6) << e;
    }
}

TEST(Trig, Atan2MatchesLibmInAllQuadrants) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> U(-1.0f, 1.0f);
    for (int i = 0; i < 200000; ++i) {
        const float y = U(rng), x = U(rng);
        ASSERT_NEAR(etk::etk_atan2(y, x), std::atan2(double(y), double(x)), 1e-6)
            << "y " << y << " x " << x;
    }
    EXPECT_EQ(etk::etk_atan2(0.0f, 1.0f), 0.0f);
    EXPECT_NEAR(etk::etk_atan2(1.0f, 0.0f), M_PI / 2, 1e-7);
    EXPECT_NEAR(etk::etk_atan2(0.0f, -1.0f), M_PI, 1e-6);
}

} // namespace
