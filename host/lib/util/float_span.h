// A range of a float buffer, as the learning names what an update rewrote and a device copies.
#pragma once
#include <cstddef>
#include <utility>
#include <vector>

namespace et {

// Floats [first, second) of a buffer.
using FloatSpan = std::pair<size_t, size_t>;

// Copies the spans `changed` of `from` (n floats) to the same places in `to` (n floats too);
// a span past them is a bug, reported before anything is copied.
void copy_spans(const float* from, size_t n, const std::vector<FloatSpan>& changed, float* to);

} // namespace et
