// The film's exact sums on a device (kernels/film_fixed.h): an OpenCL device adds passes of a
// film to the sums with the host's bits, whatever the values -- zeros, subnormals, values below
// and at half a unit, ordinary ones, values at and past the limit, infinities, NaN -- and the
// two-word arithmetic is the host's 128-bit integer arithmetic.
#include "kernels/film_fixed.h"
#include "render/film.h"
#include "render/film_sums.h"
#include "test_data.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

// The values a pass may hold, the awkward ones many times over.
float awkward_value(std::mt19937& rng) {
    const float inf = std::numeric_limits<float>::infinity();
    const float table[] = {0.0f,
                           -0.0f,
                           std::numeric_limits<float>::denorm_min(),
                           -std::numeric_limits<float>::min(),
                           std::ldexp(1.0f, -71), // half a unit: rounds away from zero
                           -std::ldexp(1.0f, -71),
                           std::ldexp(1.0f, -72), // a quarter: 0
                           std::ldexp(1.5f, -71),
                           std::ldexp(1.0f, -6), // the low word's top bit
                           std::ldexp(1.0f, -7),
                           -std::ldexp(1.0f, -6),
                           std::ldexp(16777215.0f, -30), // the mantissa across both words
                           -std::ldexp(16777215.0f, -30),
                           std::nextafter(72057594037927936.0f, 0.0f), // the largest added
                           -std::nextafter(72057594037927936.0f, 0.0f),
                           72057594037927936.0f, // 2^56: flagged
                           -72057594037927936.0f,
                           inf,
                           -inf,
                           std::numeric_limits<float>::quiet_NaN()};
    const size_t n = sizeof table / sizeof table[0];
    std::uniform_int_distribution<int> pick(0, static_cast<int>(n) + 3);
    const int k = pick(rng);
    if (k < static_cast<int>(n))
        return table[k];
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    return std::ldexp(u(rng), std::uniform_int_distribution<int>(-80, 60)(rng)); // anything
}

TEST(FilmFixed, TheDeviceAddsPassesWithTheHostsBits) {
    const int w = 61, h = 17, n = w * h, passes = 7;
    et::FilmSums host(w, h);
    et::ClRuntime& rt = ett::runtime();
    static const cl::Program program = ett::build_test_kernel(rt, "film_fixed_test.cl");
    cl::Kernel kernel(program, "fold");
    std::vector<et::FilmSums::Pixel> zeros(n, et::FilmSums::Pixel{});
    cl::Buffer sums(rt.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                    sizeof(et::FilmSums::Pixel) * n, zeros.data());
    std::mt19937 rng(5);
    for (int pass = 0; pass < passes; ++pass) {
        et::Film film(w, h);
        for (int i = 0; i < n; ++i) {
            const bool sample = rng() % 8 != 0; // a pass with no sample in some pixels
            film.film_sum[i] = etk::make_float4(awkward_value(rng), awkward_value(rng),
                                                awkward_value(rng), sample ? 1.0f : 0.0f);
            film.film_sq[i] =
                etk::make_float4(awkward_value(rng), awkward_value(rng), awkward_value(rng), 0.0f);
        }
        host.add_pass(film);
        cl::Buffer sum(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                       sizeof(etk::float4) * n, film.film_sum.data());
        cl::Buffer sq(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                      sizeof(etk::float4) * n, film.film_sq.data());
        kernel.setArg(0, sum);
        kernel.setArg(1, sq);
        kernel.setArg(2, sums);
        kernel.setArg(3, n);
        rt.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange((n + 63) / 64 * 64),
                                        cl::NDRange(64));
        rt.queue().finish();
    }
    et::FilmSums device(w, h);
    rt.queue().enqueueReadBuffer(sums, CL_TRUE, 0, sizeof(et::FilmSums::Pixel) * n, device.data());
    int flagged = 0, negative = 0;
    for (int i = 0; i < n; ++i) {
        ASSERT_EQ(std::memcmp(&host.data()[i], &device.data()[i], sizeof(et::FilmSums::Pixel)), 0)
            << "pixel " << i;
        flagged += host.data()[i].special[0] != 0;
        negative += host.data()[i].sum[1] < 0;
    }
    EXPECT_TRUE(host == device);
    // The values exercised what they were meant to: flags and negative sums both occur.
    EXPECT_GT(flagged, n / 4);
    EXPECT_GT(negative, n / 8);
}

// The conversion as the host computed it before the device shared it (128-bit arithmetic): the
// reference the two-word version must equal.
et::int128 reference_fixed_point(float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    const bool negative = bits >> 31;
    const int exponent = static_cast<int>((bits >> 23) & 0xffu);
    uint32_t mantissa = bits & 0x7fffffu;
    int e;
    if (exponent == 0) {
        e = -149;
    } else {
        mantissa |= 0x800000u;
        e = exponent - 150;
    }
    const int shift = e + et::FilmSums::kFractionBits;
    et::int128 magnitude;
    if (shift >= 0)
        magnitude = static_cast<et::int128>(mantissa) << shift;
    else if (shift > -25)
        magnitude = (static_cast<uint64_t>(mantissa) + (uint64_t(1) << (-shift - 1))) >> -shift;
    else
        magnitude = 0;
    return negative ? -magnitude : magnitude;
}

et::int128 from_words(etk::EtkFixed128 x) {
    return static_cast<et::int128>((static_cast<unsigned __int128>(x.hi) << 64) | x.lo);
}

// Every exponent that is added, with random mantissas and signs, and the ties of rounding
// (mantissas ending in a half unit) below the grid.
TEST(FilmFixed, TheTwoWordConversionEqualsTheReference) {
    std::mt19937 rng(11);
    int checked = 0;
    for (uint32_t exponent = 0; exponent < 127 + 56; ++exponent) {
        for (int k = 0; k < 4000; ++k) {
            uint32_t mantissa = rng() & 0x7fffffu;
            if (k % 4 == 0) // a tie or near one where the grid cuts the mantissa
                mantissa = (mantissa & ~0xffu) | (k % 8 == 0 ? 0x80u : 0x7fu);
            const uint32_t bits = (rng() & 0x80000000u) | (exponent << 23) | mantissa;
            float v;
            std::memcpy(&v, &bits, sizeof v);
            if (etk::etk_fixed_special(v) != 0u)
                continue;
            ASSERT_EQ(from_words(etk::etk_fixed_from_float(v)), reference_fixed_point(v))
                << std::hexfloat << v;
            ++checked;
        }
    }
    EXPECT_GT(checked, 700000);
}

// The two words are a 128-bit two's complement number: a value and its negation add to zero
// with the carry through the high word, and a value straddling the words lands in both.
TEST(FilmFixed, TwoWordsAreTheHostsInt128) {
    for (int e = -80; e <= 55; ++e) {
        SCOPED_TRACE(e);
        const float v = std::ldexp(1.3f, e);
        const etk::EtkFixed128 p = etk::etk_fixed_from_float(v), m = etk::etk_fixed_from_float(-v);
        const et::int128 pv =
            static_cast<et::int128>((static_cast<unsigned __int128>(p.hi) << 64) | p.lo);
        const et::int128 mv =
            static_cast<et::int128>((static_cast<unsigned __int128>(m.hi) << 64) | m.lo);
        EXPECT_EQ(pv, -mv);
        // Within half a unit of v x 2^70 (the float's exact value in units).
        const long double exact = std::ldexp(static_cast<long double>(v), 70);
        EXPECT_LE(std::fabs(static_cast<long double>(pv) - exact), 0.5L);
    }
    const etk::EtkFixed128 top = etk::etk_fixed_from_float(std::ldexp(1.0f, -6)); // 2^64 units
    EXPECT_EQ(top.lo, 0u);
    EXPECT_EQ(top.hi, 1u);
    const etk::EtkFixed128 below = etk::etk_fixed_from_float(-std::ldexp(1.0f, -6));
    EXPECT_EQ(below.lo, 0u);
    EXPECT_EQ(below.hi, ~uint64_t(0)); // -2^64
}

} // namespace
