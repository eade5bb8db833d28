// The host's lane-mask helpers of the shared kernels (kernels/compat.h), which the BVH traversal
// branches on, against a lane-by-lane reference: every pattern of eight and of four lanes, lane 7
// and the sign of zero and of NaN included. A mask that sign-extends its top lane into bits 8-31
// (GCC's raw AVX-512 compare builtin returns a signed char) or reads the wrong lane fails here
// rather than as a traversal that pushes nonexistent children.
#include "kernels/compat.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace {

using etk::float4;
using etk::float8;

float with_bits(uint32_t b) {
    float f;
    std::memcpy(&f, &b, sizeof f);
    return f;
}
uint32_t bits_of(float f) {
    uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}

TEST(LaneMasks, LessOrEqualBitsOfEveryPattern) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (uint32_t want = 0; want < 256; ++want) {
        for (int variant = 0; variant < 3; ++variant) {
            float8 a, b;
            for (int i = 0; i < 8; ++i) {
                const bool le = (want >> i) & 1u;
                if (variant == 0) { // ordinary values, equal ones among the true lanes
                    a[i] = le ? (i % 2 ? 1.0f : 2.0f) : 3.0f;
                    b[i] = 2.0f;
                } else if (variant == 1) { // zeros of both signs are equal
                    a[i] = le ? -0.0f : 1e-30f;
                    b[i] = 0.0f;
                } else { // NaN compares false
                    a[i] = le ? -1e30f : nan;
                    b[i] = le ? 1e30f : 0.0f;
                }
            }
            ASSERT_EQ(etk::etk_le_bits8(a, b), want)
                << "pattern " << want << " variant " << variant;
            ASSERT_EQ(etk::etk_lane_bits8(a <= b), want) << "pattern " << want;
        }
    }
}

TEST(LaneMasks, SignBitsOfEveryPattern) {
    for (uint32_t want = 0; want < 256; ++want) {
        float8 v;
        for (int i = 0; i < 8; ++i) {
            const bool neg = (want >> i) & 1u;
            // Leaf flags are integers stored as float bits: 0x80000000 | count, or 0.
            const uint32_t mag =
                i == 3 ? 0x7fc00000u : (i == 5 ? 0u : 7u + static_cast<uint32_t>(i));
            v[i] = with_bits((neg ? 0x80000000u : 0u) | mag);
        }
        ASSERT_EQ(etk::etk_sign_bits8(v), want) << "pattern " << want;
    }
}

TEST(LaneMasks, FourLaneBitsOfEveryPattern) {
    for (uint32_t want = 0; want < 16; ++want) {
        float4 a{}, b{};
        float av[4], bv[4];
        for (int i = 0; i < 4; ++i) {
            av[i] = (want >> i) & 1u ? -2.0f : 5.0f;
            bv[i] = 1.0f;
        }
        a = etk::make_float4(av[0], av[1], av[2], av[3]);
        b = etk::make_float4(bv[0], bv[1], bv[2], bv[3]);
        ASSERT_EQ(etk::etk_lane_bits4(etk::etk_lanes_of(a) <= etk::etk_lanes_of(b)), want)
            << "pattern " << want;
    }
}

TEST(LaneMasks, FabsOfFourLanesClearsTheSignBitOnly) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float4 r = etk::fabs(etk::make_float4(-0.0f, -3.5f, 2.0f, -nan));
    EXPECT_EQ(bits_of(r.x), 0u); // +0, as OpenCL's fabs
    EXPECT_EQ(r.y, 3.5f);
    EXPECT_EQ(r.z, 2.0f);
    EXPECT_TRUE(std::isnan(r.w));
    EXPECT_EQ(bits_of(r.w) >> 31, 0u);
}

} // namespace
