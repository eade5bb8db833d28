// The samplers of kernels/sampler.h: the scrambled (0,2)-sequence keeps its elementary-interval
// property for every scramble and aligned block, values are pure functions of (seed, stream,
// index, pair), and the OpenCL kernel produces the host's values bit for bit.
#include "kernels/sampler.h"
#include "test_data.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>

namespace {

using etk::etk_sample_pair;

struct Key {
    uint32_t seed, stream, pair;
};
const Key kKeys[] = {{0, 0, 0}, {1, 0, 0},  {1, 1, 0},
                     {1, 0, 1}, {42, 7, 3}, {0xdeadbeef, 123456, 9}};

// Every 2^i x 2^(m-i) box of [0,1)^2 holds exactly one of the 2^m points.
::testing::AssertionResult is_02_net(const std::vector<etk::float2>& pts, int m) {
    const size_t n = size_t(1) << m;
    if (pts.size() != n)
        return ::testing::AssertionFailure() << "wrong point count";
    std::vector<int> count(n);
    for (int i = 0; i <= m; ++i) {
        std::fill(count.begin(), count.end(), 0);
        const float sx = static_cast<float>(1u << i), sy = static_cast<float>(1u << (m - i));
        for (const auto& p : pts) {
            if (!(p.x >= 0.0f && p.x < 1.0f && p.y >= 0.0f && p.y < 1.0f))
                return ::testing::AssertionFailure() << "point outside [0,1)^2";
            const size_t bx = static_cast<size_t>(p.x * sx), by = static_cast<size_t>(p.y * sy);
            if (++count[by * (size_t(1) << i) + bx] > 1)
                return ::testing::AssertionFailure()
                       << "two points in the elementary interval " << (1u << i) << " x "
                       << (1u << (m - i)) << " box (" << bx << ", " << by << ")";
        }
    }
    return ::testing::AssertionSuccess();
}

std::vector<etk::float2> block(const Key& k, uint32_t first, int m) {
    std::vector<etk::float2> pts;
    for (uint32_t i = 0; i < (1u << m); ++i)
        pts.push_back(etk_sample_pair(ETK_SAMPLER_SOBOL, k.seed, k.stream, first + i, k.pair));
    return pts;
}

TEST(Sampler, FirstPointsAreElementaryIntervalNets) {
    for (const Key& k : kKeys)
        for (int m = 0; m <= 10; ++m)
            EXPECT_TRUE(is_02_net(block(k, 0, m), m))
                << "seed " << k.seed << " stream " << k.stream << " pair " << k.pair << " m " << m;
}

TEST(Sampler, AlignedBlocksAreElementaryIntervalNets) {
    for (const Key& k : kKeys)
        for (int m = 0; m <= 10; ++m)
            for (uint32_t b : {1u, 2u, 5u, 1000u, (1u << (31 - m)) - 1u})
                EXPECT_TRUE(is_02_net(block(k, b << m, m), m))
                    << "seed " << k.seed << " stream " << k.stream << " pair " << k.pair << " m "
                    << m << " block " << b;
}

// Misaligned blocks of 2^m are not nets in general: the check above is not vacuous.
TEST(Sampler, NetCheckRejectsMisalignedBlocks) {
    int rejected = 0;
    for (const Key& k : kKeys)
        rejected += !is_02_net(block(k, 3, 6), 6);
    EXPECT_GT(rejected, 0);
}

TEST(Sampler, ScramblesDifferBetweenStreamsAndPairs) {
    const auto a = block({1, 0, 0}, 0, 8), b = block({1, 1, 0}, 0, 8), c = block({1, 0, 1}, 0, 8),
               d = block({2, 0, 0}, 0, 8);
    auto same = [](const std::vector<etk::float2>& p, const std::vector<etk::float2>& q) {
        for (size_t i = 0; i < p.size(); ++i)
            if (p[i].x != q[i].x || p[i].y != q[i].y)
                return false;
        return true;
    };
    EXPECT_FALSE(same(a, b));
    EXPECT_FALSE(same(a, c));
    EXPECT_FALSE(same(a, d));
}

TEST(Sampler, SameKeyGivesSameValueInAnyOrder) {
    for (int sampler : {ETK_SAMPLER_SOBOL, ETK_SAMPLER_RANDOM}) {
        std::vector<uint32_t> idx(4096);
        for (uint32_t i = 0; i < idx.size(); ++i)
            idx[i] = i * 7919u;
        std::vector<etk::float2> forward;
        for (uint32_t i : idx)
            forward.push_back(etk_sample_pair(sampler, 5u, 11u, i, 2u));
        std::vector<size_t> order(idx.size());
        for (size_t i = 0; i < order.size(); ++i)
            order[i] = i;
        std::shuffle(order.begin(), order.end(), std::mt19937(1234));
        for (size_t o : order) {
            // Interleave other keys between the visits: no hidden state may leak.
            (void)etk_sample_pair(sampler, 6u, 12u, idx[o] + 1u, 0u);
            const etk::float2 v = etk_sample_pair(sampler, 5u, 11u, idx[o], 2u);
            ASSERT_EQ(etk::as_uint(v.x), etk::as_uint(forward[o].x)) << "index " << idx[o];
            ASSERT_EQ(etk::as_uint(v.y), etk::as_uint(forward[o].y)) << "index " << idx[o];
        }
    }
}

TEST(Sampler, RandomValuesInUnitIntervalAndUniform) {
    // Values in [0,1), and a coarse uniformity check (mean and a 16-bin histogram per axis).
    const int n = 1 << 16;
    std::vector<int> hx(16), hy(16);
    double sx = 0, sy = 0;
    for (uint32_t i = 0; i < static_cast<uint32_t>(n); ++i) {
        const etk::float2 v = etk_sample_pair(ETK_SAMPLER_RANDOM, 99u, 3u, i, 1u);
        ASSERT_TRUE(v.x >= 0.0f && v.x < 1.0f && v.y >= 0.0f && v.y < 1.0f) << "index " << i;
        ++hx[static_cast<int>(v.x * 16)];
        ++hy[static_cast<int>(v.y * 16)];
        sx += v.x;
        sy += v.y;
    }
    // Standard error of the mean is 1/sqrt(12 n) ~ 0.0011; of a bin count sqrt(n/16 * 15/16) ~ 62.
    EXPECT_NEAR(sx / n, 0.5, 5 * 0.0012);
    EXPECT_NEAR(sy / n, 0.5, 5 * 0.0012);
    for (int b = 0; b < 16; ++b) {
        EXPECT_NEAR(hx[b], n / 16, 5 * 62);
        EXPECT_NEAR(hy[b], n / 16, 5 * 62);
    }
}

TEST(Sampler, SobolValuesStayBelowOne) {
    // Scrambles with all bits set push values to the top of the range: still below one.
    for (uint32_t i = 0; i < 1024; ++i)
        for (uint32_t s : {0u, 0xffffffffu, 0xffffff00u}) {
            const float x = etk::etk_unit_float(etk::etk_sobol02_x(i, s));
            const float y = etk::etk_unit_float(etk::etk_sobol02_y(i, s));
            ASSERT_LT(x, 1.0f);
            ASSERT_LT(y, 1.0f);
            ASSERT_GE(x, 0.0f);
            ASSERT_GE(y, 0.0f);
        }
}

TEST(Sampler, ShuffleIsAPermutationOfAlignedBlocks) {
    for (uint32_t seed : {0u, 1u, 0x12345678u})
        for (int m = 0; m <= 10; ++m)
            for (uint32_t b : {0u, 3u}) {
                std::vector<uint32_t> out;
                for (uint32_t i = 0; i < (1u << m); ++i)
                    out.push_back(etk::etk_shuffle_index((b << m) + i, seed) >> m);
                // Every index of the block maps into one and the same aligned block...
                EXPECT_TRUE(
                    std::all_of(out.begin(), out.end(), [&](uint32_t v) { return v == out[0]; }))
                    << "seed " << seed << " m " << m;
                // ... and bijectively.
                std::vector<uint32_t> low;
                for (uint32_t i = 0; i < (1u << m); ++i)
                    low.push_back(etk::etk_shuffle_index((b << m) + i, seed) & ((1u << m) - 1));
                std::sort(low.begin(), low.end());
                for (uint32_t i = 0; i < low.size(); ++i)
                    ASSERT_EQ(low[i], i) << "seed " << seed << " m " << m;
            }
}

TEST(Sampler, KernelMatchesHostBitForBit) {
    et::ClRuntime& rt = ett::runtime();
    cl::Program program = ett::build_test_kernel(rt, "sampler_test.cl");
    cl::Kernel kernel(program, "sample_pairs");
    const int n = 4096;
    for (int sampler : {ETK_SAMPLER_SOBOL, ETK_SAMPLER_RANDOM})
        for (const Key& k : kKeys)
            for (uint32_t first : {0u, 4096u * 3u, 0xfffff000u}) {
                cl::Buffer out(rt.context(), CL_MEM_WRITE_ONLY, sizeof(float) * 2 * n);
                kernel.setArg(0, sampler);
                kernel.setArg(1, k.seed);
                kernel.setArg(2, k.stream);
                kernel.setArg(3, first);
                kernel.setArg(4, k.pair);
                kernel.setArg(5, n);
                kernel.setArg(6, out);
                rt.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(n),
                                                cl::NDRange(64));
                std::vector<float> v(2 * n);
                rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, v.size() * sizeof(float), v.data());
                for (int i = 0; i < n; ++i) {
                    const etk::float2 h =
                        etk_sample_pair(sampler, k.seed, k.stream, first + i, k.pair);
                    ASSERT_EQ(etk::as_uint(v[2 * i]), etk::as_uint(h.x))
                        << "sampler " << sampler << " index " << first + i;
                    ASSERT_EQ(etk::as_uint(v[2 * i + 1]), etk::as_uint(h.y))
                        << "sampler " << sampler << " index " << first + i;
                }
            }
}

} // namespace

namespace {

// The second Sobol' dimension by its definition: direction numbers v_0 = 2^31, v_k = v_(k-1) ^
// (v_(k-1) >> 1), xored for every set bit of the index (what etk_sobol_dim1 computed before
// its zeta-transform form).
uint32_t sobol_dim1_by_direction_numbers(uint32_t i) {
    uint32_t v = 0x80000000u, r = 0u;
    for (int k = 0; k < 32; ++k, v ^= v >> 1)
        if ((i >> k) & 1u)
            r ^= v;
    return r;
}

TEST(Sampler, SobolDimensionOneEqualsTheDirectionNumbers) {
    std::mt19937 rng(7);
    std::vector<uint32_t> idx = {0u, 1u, 2u, 3u, 0x80000000u, 0xffffffffu, 0x7fffffffu};
    for (uint32_t i = 0; i < 70000; ++i)
        idx.push_back(i);
    for (int k = 0; k < 200000; ++k)
        idx.push_back(rng());
    for (uint32_t i : idx) {
        ASSERT_EQ(etk::etk_sobol_dim1(i), sobol_dim1_by_direction_numbers(i)) << i;
        ASSERT_EQ(etk::etk_sobol_dim1_reversed(etk::etk_reverse_bits(i)),
                  sobol_dim1_by_direction_numbers(i))
            << i;
    }
}

// etk_sample_pair's Sobol' branch works on the reversed shuffled index; it must equal the
// composition of the sequence functions it stands for.
TEST(Sampler, PairEqualsTheSequenceFunctions) {
    for (const Key& k : kKeys)
        for (uint32_t first : {0u, 1000u, 0xfffff000u})
            for (uint32_t index = first; index < first + 2048u; ++index) {
                const uint32_t key =
                    etk::etk_hash_combine(etk::etk_hash_combine(k.seed, k.stream), k.pair);
                const uint32_t i = etk::etk_shuffle_index(index, etk::etk_hash(key ^ 0x5bd1e995u));
                const etk::float2 want = etk::make_float2(
                    etk::etk_unit_float(etk::etk_sobol02_x(i, etk::etk_hash(key ^ 0x68e31da4u))),
                    etk::etk_unit_float(etk::etk_sobol02_y(i, etk::etk_hash(key ^ 0xb5297a4du))));
                const etk::float2 got =
                    etk::etk_sample_pair(ETK_SAMPLER_SOBOL, k.seed, k.stream, index, k.pair);
                ASSERT_EQ(etk::as_uint(got.x), etk::as_uint(want.x)) << index;
                ASSERT_EQ(etk::as_uint(got.y), etk::as_uint(want.y)) << index;
            }
}

} // namespace
