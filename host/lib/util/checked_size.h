// Size arithmetic for buffers built from user input: 64-bit, checked, and bounded by what the
// host can hold and what the device can index (kernels index with 32-bit ints).
#pragma once
#include "util/error.h"

#include <cstdint>
#include <limits>
#include <string>

namespace et {

// The largest element count a kernel may index: its offsets are 32-bit ints.
constexpr uint64_t kMaxDeviceIndex = static_cast<uint64_t>(std::numeric_limits<int32_t>::max());

// The most bytes one host buffer built from an input (texels, distribution table) may take.
constexpr uint64_t kMaxBufferBytes = uint64_t(3) << 30;

// a * b, or et::Error "what: ... too large" when the product does not fit in 64 bits.
inline uint64_t checked_mul(uint64_t a, uint64_t b, const std::string& what) {
    uint64_t r;
    if (__builtin_mul_overflow(a, b, &r))
        throw Error(what + ": size overflows 64 bits");
    return r;
}

inline uint64_t checked_add(uint64_t a, uint64_t b, const std::string& what) {
    uint64_t r;
    if (__builtin_add_overflow(a, b, &r))
        throw Error(what + ": size overflows 64 bits");
    return r;
}

} // namespace et
