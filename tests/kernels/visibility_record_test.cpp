// The visibility strategy's shadow-ray records summed where they are made
// (kernels/visibility_record.h): 64-bit sums from 32-bit atomics must carry exactly whatever the
// order and the threads, and an OpenCL device must sum a batch of records to the host's bits.
#include "kernels/visibility_record.h"
#include "test_data.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <thread>
#include <vector>

namespace {

uint64_t wide(const uint32_t* w) {
    return uint64_t(w[0]) | uint64_t(w[1]) << 32;
}

// Values up to 2^41 from two threads at once, many of whose low words overflow: the pair holds
// their exact sum.
TEST(VisibilityRecord, WideAddsCarryFromConcurrentThreads) {
    std::vector<uint32_t> pair(2, 0u);
    uint64_t expected[2] = {0, 0};
    auto add = [&](int t) {
        std::mt19937_64 rng(7 + t);
        for (int i = 0; i < 200000; ++i) {
            const uint64_t v = i % 3 == 0 ? 0xffffffffull : rng() >> 23; // < 2^41
            etk::etk_add_wide(pair.data(), v);
            expected[t] += v;
        }
    };
    std::thread a(add, 0), b(add, 1);
    a.join();
    b.join();
    EXPECT_EQ(wide(pair.data()), expected[0] + expected[1]);
}

TEST(VisibilityRecord, FixedPointIsCappedAndRounded) {
    EXPECT_EQ(etk::etk_guide_fixed(0.0f), 0u);
    EXPECT_EQ(etk::etk_guide_fixed(1.0f), uint64_t(1) << 28);
    EXPECT_EQ(etk::etk_guide_fixed(1.5f / 268435456.0f), 2u); // half a unit rounds up
    EXPECT_EQ(etk::etk_guide_fixed(1.0e30f), uint64_t(1) << 40);
    EXPECT_EQ(etk::etk_guide_fixed(std::numeric_limits<float>::infinity()), uint64_t(1) << 40);
}

// Records of every kind -- keys in and outside the table, blocked and unblocked, values of 0,
// negative, non-finite or past the cap, densities of 0 and NaN -- summed natively and by the
// OpenCL device, 64 records per work-group racing for the same few cells: the same words.
TEST(VisibilityRecord, DeviceSumsEqualTheHostsBitForBit) {
    constexpr int slots = 16, n = 20000;
    etk::EtkParams p{};
    p.guide_slots = slots;
    p.guide_inv_power = 0.37f;
    std::vector<float> box(ETK_PORTAL_SHARES + slots, 0.0f);
    for (int s = 0; s < slots; ++s)
        box[ETK_PORTAL_SHARES + s] = etk::etk_portal_candidate(s % ETK_PORTAL_CANDIDATES);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<int> keys(n), exits(n);
    std::vector<float> values(n), parts(2 * n);
    const float odd[] = {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                         std::numeric_limits<float>::infinity(), 1.0e9f};
    for (int i = 0; i < n; ++i) {
        keys[i] = i % 97 == 0 ? -1
                              : (i % 89 == 0 ? slots * ETK_GUIDE_REGIONS
                                             : int(rng() % (slots * ETK_GUIDE_REGIONS)));
        exits[i] = i % 5 == 0 ? -1 : int(rng() % 12); // a window's few cells
        values[i] = i % 13 == 0 ? odd[(i / 13) % 5] : 50.0f * u(rng) * u(rng);
        parts[2 * i] = i % 31 == 0 ? 0.0f : u(rng);
        parts[2 * i + 1] = i % 37 == 0 ? std::numeric_limits<float>::quiet_NaN() : 3.0f * u(rng);
    }
    const size_t words = static_cast<size_t>(etk::etk_gsum_words(slots, 0));
    std::vector<uint32_t> host(words, 0u);
    for (int i = 0; i < n; ++i)
        etk::etk_guide_record_light(host.data(), p, box.data(), keys[i], values[i], exits[i],
                                    etk::make_float2(parts[2 * i], parts[2 * i + 1]));
    EXPECT_GT(host[etk::etk_gsum_counts(slots) + 3], 0u);

    et::ClRuntime& rt = ett::runtime();
    cl::Program program = ett::build_test_kernel(rt, "visibility_record_test.cl");
    cl::Kernel kernel(program, "record_lights");
    auto& ctx = rt.context();
    std::vector<uint32_t> zero(words, 0u);
    cl::Buffer sums(ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, words * 4, zero.data());
    cl::Buffer b_box(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, box.size() * 4, box.data());
    cl::Buffer b_keys(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, size_t(n) * 4, keys.data());
    cl::Buffer b_values(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, size_t(n) * 4, values.data());
    cl::Buffer b_exits(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, size_t(n) * 4, exits.data());
    cl::Buffer b_parts(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, size_t(n) * 8, parts.data());
    kernel.setArg(0, sums);
    kernel.setArg(1, sizeof(p), &p);
    kernel.setArg(2, b_box);
    kernel.setArg(3, b_keys);
    kernel.setArg(4, b_values);
    kernel.setArg(5, b_exits);
    kernel.setArg(6, b_parts);
    kernel.setArg(7, n);
    rt.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange((n + 63) / 64 * 64),
                                    cl::NDRange(64));
    std::vector<uint32_t> device(words);
    rt.queue().enqueueReadBuffer(sums, CL_TRUE, 0, words * 4, device.data());
    for (size_t k = 0; k < words; ++k)
        ASSERT_EQ(device[k], host[k]) << "word " << k;
}

} // namespace
