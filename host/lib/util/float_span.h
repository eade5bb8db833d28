// A range of a float buffer, as the learning names what an update rewrote and a device copies.
#pragma once
#include <cstddef>
#include <utility>

namespace et {

// Floats [first, second) of a buffer.
using FloatSpan = std::pair<size_t, size_t>;

} // namespace et
