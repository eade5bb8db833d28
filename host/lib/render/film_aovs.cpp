#include "render/film_aovs.h"

namespace et {

void add_aov_pass(AovPixel* to, const etk::float4* albedo, const etk::float4* normal, size_t n) {
    for (size_t i = 0; i < n; ++i) {
        AovPixel& p = to[i];
        const etk::float4 a = albedo[i], nd = normal[i];
        if (a.w == 0.0f)
            continue; // no hit this pass: nothing was written, the pass holds zeros
        const float v[AovPixel::kValues] = {a.x, a.y, a.z, nd.x, nd.y, nd.z, nd.w};
        for (int k = 0; k < AovPixel::kValues; ++k)
            film_accumulate(p.sum[k], p.special[k], v[k]);
        p.hits += 1;
    }
}

void add_aov_pixels(AovPixel* to, const AovPixel* from, size_t n) {
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < AovPixel::kValues; ++k) {
            to[i].sum[k] += from[i].sum[k];
            to[i].special[k] |= from[i].special[k];
        }
        to[i].hits += from[i].hits;
    }
}

} // namespace et
