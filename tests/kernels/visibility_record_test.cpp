// The visibility strategy's shadow-ray records summed where they are made
// (kernels/visibility_record.h): 64-bit sums from 32-bit atomics must carry exactly whatever the
// order and the threads, and an OpenCL device must sum a batch of records to the host's bits.
#include "kernels/visibility_record.h"
#include "prepare/visibility_tables.h"
#include "test_data.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
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

// A read-only device copy of v.
template <typename T> cl::Buffer input(const std::vector<T>& v) {
    return cl::Buffer(ett::runtime().context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                      v.size() * sizeof(T), const_cast<T*>(v.data()));
}

// Runs test kernel `name` over n records -- arguments: the sums (zeroed), p, `inputs`, n -- and
// returns its sums of `words` words.
std::vector<uint32_t> device_sums(const char* name, const etk::EtkParams& p,
                                  const std::vector<cl::Buffer>& inputs, int n, size_t words) {
    et::ClRuntime& rt = ett::runtime();
    static const cl::Program program = ett::build_test_kernel(rt, "visibility_record_test.cl");
    cl::Kernel kernel(program, name);
    std::vector<uint32_t> out(words, 0u);
    cl::Buffer sums(rt.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, words * 4, out.data());
    kernel.setArg(0, sums);
    kernel.setArg(1, sizeof(p), &p);
    for (size_t a = 0; a < inputs.size(); ++a)
        kernel.setArg(static_cast<cl_uint>(2 + a), inputs[a]);
    kernel.setArg(static_cast<cl_uint>(2 + inputs.size()), n);
    rt.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange((n + 63) / 64 * 64),
                                    cl::NDRange(64));
    rt.queue().enqueueReadBuffer(sums, CL_TRUE, 0, words * 4, out.data());
    return out;
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
    std::vector<float> values(n), reaches(n), parts(2 * n);
    const float odd[] = {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                         std::numeric_limits<float>::infinity(), 1.0e9f};
    for (int i = 0; i < n; ++i) {
        keys[i] = i % 97 == 0 ? -1
                              : (i % 89 == 0 ? slots * ETK_GUIDE_REGIONS
                                             : int(rng() % (slots * ETK_GUIDE_REGIONS)));
        exits[i] = i % 5 == 0 ? -1 : int(rng() % 12); // a window's few cells
        values[i] = i % 13 == 0 ? odd[(i / 13) % 5] : 50.0f * u(rng) * u(rng);
        // A blocked ray's value is 0 and its reach what it would have brought.
        reaches[i] = values[i] + (exits[i] < 0 ? 10.0f * u(rng) : 0.0f);
        values[i] = exits[i] < 0 ? 0.0f : values[i];
        parts[2 * i] = i % 31 == 0 ? 0.0f : u(rng);
        parts[2 * i + 1] = i % 37 == 0 ? std::numeric_limits<float>::quiet_NaN() : 3.0f * u(rng);
    }
    const size_t words = static_cast<size_t>(etk::etk_gsum_words(slots, 0));
    std::vector<uint32_t> host(words, 0u);
    for (int i = 0; i < n; ++i)
        etk::etk_guide_record_light(host.data(), p, box.data(), keys[i], values[i], reaches[i],
                                    exits[i], etk::make_float2(parts[2 * i], parts[2 * i + 1]));
    EXPECT_GT(host[etk::etk_gsum_cell(slots, 0, 3) + ETK_GSUM_COUNT], 0u);
    EXPECT_GT(host[etk::etk_gsum_cell(slots, 0, 3) + ETK_GSUM_REACH + 1], 0u);

    const std::vector<uint32_t> device = device_sums(
        "record_lights", p,
        {input(box), input(keys), input(values), input(reaches), input(exits), input(parts)}, n,
        words);
    for (size_t k = 0; k < words; ++k)
        ASSERT_EQ(device[k], host[k]) << "word " << k;
}

// Continuation records against tables with learned guides, shares and a secondary-source table,
// before and after the first update (the guided share's moments count only after it): the
// device's words are the host's.
TEST(VisibilityRecord, DeviceContinuationSumsEqualTheHostsBitForBit) {
    constexpr int slots = 16, n = 20000;
    const std::array<float, 6> box{{-1.0f, -1.0f, -1.0f, 2.0f, 1.5f, 1.0f}};
    std::vector<float> cells = et::guide_prior_cells(
        std::vector<float>(ETK_GUIDE_REGIONS, 1.0f / ETK_GUIDE_REGIONS), slots, true, box);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int s = 0; s < slots; ++s) { // a learned guide and a share per cell
        std::vector<double> prob(ETK_GUIDE_REGIONS);
        for (double& q : prob)
            q = u(rng) < 0.2f ? 0.0 : u(rng);
        float* dir = cells.data() + etk::etk_guide_dir_offset(slots, s);
        et::write_guide_cdf(prob, dir);
        dir[ETK_GUIDE_DIR_SHARE] = etk::etk_guided_candidate(s % ETK_GUIDED_CANDIDATES);
    }
    std::vector<float> shares(slots);
    std::vector<double> spot(ETK_PORTAL_CELLS);
    for (int s = 0; s < slots; ++s)
        shares[s] = etk::etk_portal_candidate(s % ETK_PORTAL_CANDIDATES);
    for (double& v : spot)
        v = u(rng) < 0.5f ? 0.0 : u(rng);
    et::write_portal_table(box, shares, spot,
                           cells.data() + etk::etk_portal_offset(slots, 1) +
                               etk::etk_portal_size(slots));
    std::vector<int> keys(n);
    std::vector<float> values(n), rays(8 * n);
    const float odd[] = {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                         std::numeric_limits<float>::infinity(), 1.0e9f};
    for (int i = 0; i < n; ++i) {
        keys[i] = i % 97 == 0 ? -1 : int(rng() % (slots * ETK_GUIDE_REGIONS));
        values[i] = i % 13 == 0 ? odd[(i / 13) % 5] : 20.0f * u(rng) * u(rng);
        const float z = 2.0f * u(rng) - 1.0f, phi = 6.2831853f * u(rng);
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        const float ray[8] = {-0.5f + u(rng),
                              -0.5f + u(rng),
                              -0.5f + u(rng),
                              i % 31 == 0 ? 0.0f : 0.05f + u(rng),
                              r * std::cos(phi),
                              r * std::sin(phi),
                              z,
                              0.0f};
        std::copy(ray, ray + 8, rays.begin() + 8 * i);
    }
    const size_t words = static_cast<size_t>(etk::etk_gsum_words(slots, 1));
    for (int ready : {0, 1}) {
        etk::EtkParams p{};
        p.guide_slots = slots;
        p.guide_inv_power = 0.61f;
        p.guide_continuation = 1;
        p.guide_continuation_share = 0.5f;
        p.guide_ready = ready;
        std::vector<uint32_t> host(words, 0u);
        for (int i = 0; i < n; ++i) {
            const float* r = rays.data() + 8 * i;
            etk::etk_guide_record_continuation(host.data(), p, cells.data(), keys[i], values[i],
                                               etk::make_float3(r[0], r[1], r[2]),
                                               etk::make_float3(r[4], r[5], r[6]), r[3]);
        }
        EXPECT_GT(host[etk::etk_gsum_cell(slots, 1, 3) + ETK_GSUM_DCOUNT], 0u);
        if (ready) {
            EXPECT_GT(host[etk::etk_gsum_cell(slots, 1, 3) + ETK_GSUM_GCOUNT], 0u)
                << "no guided-share moment";
        }
        const std::vector<uint32_t> device =
            device_sums("record_continuations", p,
                        {input(cells), input(keys), input(values), input(rays)}, n, words);
        for (size_t k = 0; k < words; ++k)
            ASSERT_EQ(device[k], host[k]) << "ready " << ready << ", word " << k;
    }
}

} // namespace
