// Film accumulation (kernels/integrator.h, etk_accumulate; kernels/film.h): a non-finite path
// radiance is left out of the pixel and counted, so renders report it instead of writing NaN.
#include "kernels/integrator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

TEST(Integrator, AccumulateDropsAndCountsNonFiniteSamples) {
    using etk::float4;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float4> radiance = {
        {1, 2, 3, 0}, {nan, 0, 0, 0}, {0, inf, 0, 0}, {0.5f, 0.5f, 0.5f, 0}};
    std::vector<int> pixel = {0, 1, 2, 0};
    std::vector<float4> film(3, float4{0, 0, 0, 0}), film_sq(3, float4{0, 0, 0, 0});
    uint32_t counters[etk::ETK_Q_COUNT] = {};
    etk::EtkPaths P{};
    P.radiance = radiance.data();
    P.pixel = pixel.data();
    etk::EtkQueues Q{};
    Q.counters = counters;
    etk::EtkFilm F{}; // accumulate writes the radiance sums only
    F.film_sum = film.data();
    F.film_sq = film_sq.data();
    for (int i = 0; i < 4; ++i)
        etk::etk_accumulate(etk::EtkScene{}, P, Q, F, etk::EtkParams{}, i);
    EXPECT_EQ(counters[etk::ETK_Q_NONFINITE], 2u);
    EXPECT_FLOAT_EQ(film_sq[0].x, 1.25f); // 1^2 + 0.5^2: the sums of squares
    EXPECT_FLOAT_EQ(film_sq[0].z, 9.25f);
    EXPECT_FLOAT_EQ(film[0].x, 1.5f);
    EXPECT_FLOAT_EQ(film[0].w, 2.0f); // both samples counted towards the pixel's mean
    for (int p = 1; p < 3; ++p) {
        EXPECT_TRUE(std::isfinite(film[p].x) && std::isfinite(film[p].y) &&
                    std::isfinite(film[p].z));
        EXPECT_EQ(film[p].w, 1.0f);
    }
}
