#include "util/float_span.h"

#include "util/error.h"

#include <algorithm>
#include <string>

namespace et {

void copy_spans(const float* from, size_t n, const std::vector<FloatSpan>& changed, float* to) {
    for (const auto& [first, end] : changed)
        if (first > end || end > n)
            throw Error("visibility tables' span " + std::to_string(first) + " .. " +
                        std::to_string(end) + " past their " + std::to_string(n) +
                        " floats (a bug)");
    for (const auto& [first, end] : changed)
        std::copy(from + first, from + end, to + first);
}

} // namespace et
