// Multiple importance sampling's weights (Veach 1997), for the light sample and the BSDF sample
// of a vertex, and for the resampled light sample's target (light_resampling.h).
#ifndef ETK_MIS_H
#define ETK_MIS_H
#include "compat.h"
#include "params.h"

ETK_BEGIN

ETK_FN float etk_mis_weight(int heuristic, float a, float b) {
    if (heuristic == ETK_HEURISTIC_POWER) {
        a *= a;
        b *= b;
    }
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

// The MIS weight of a light sample (density pl; p_bsdf pb there) and of a BSDF sample (pb; pl),
// each over its count: with nl = lc x p.light_samples light samples and nb = p.bsdf_samples BSDF
// samples expected per vertex (the mis strategy's splitting, etk_split_samples; lc < 1 where the
// visibility strategy takes its light sample with probability lc, etk_guide_light_count), the
// multi-sample heuristic's weight on nl pl and nb pb (Veach), divided by the technique's count.
// nl = nb = 1: the paper's weights, bit for bit.
// Forced inline: a call would copy EtkParams, as etk_dims would (surface.h).
ETK_FORCE_INLINE_FN float etk_light_sample_weight(EtkParams p, float lc, float pl, float pb) {
    float nl = lc * (float)p.light_samples;
    return etk_mis_weight(p.heuristic, nl * pl, (float)p.bsdf_samples * pb) / nl;
}
ETK_FORCE_INLINE_FN float etk_bsdf_sample_weight(EtkParams p, float lc, float pb, float pl) {
    float nb = (float)p.bsdf_samples;
    return etk_mis_weight(p.heuristic, nb * pb, lc * (float)p.light_samples * pl) / nb;
}

ETK_END

#endif
