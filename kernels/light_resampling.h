// Resampled importance sampling of a vertex's light sample (Talbot et al. 2005; the unbiased
// contribution weight of Bitterli et al. 2020 and Lin et al. 2022): n candidate directions from
// the vertex's light technique, one of them kept with probability proportional to its target
// luminance(f L) |cos| / p, so the kept direction follows the product of the map and the BSDF's
// lobe that the map's distribution alone cannot see (a glossy lobe, the cosine). No table, no
// learning: the same on every device and from the first sample.
//
// Unbiased for any n: the kept sample y with weight W = (sum of w_j / n) / target(y) estimates the
// integral of any g that vanishes where the target does, because each candidate alone follows the
// technique's density p (E[g(y) W] = (1/n) sum_j E[g(x_j) / p(x_j)]), however the candidates
// depend on each other. So the candidates are the vertex's sample point shifted by a rank-1
// lattice (etk_lattice_point): stratified, which lowers the kept sample's variance. The target
// has the integrand's support (f L cos > 0 where the luminance is: its weights are positive), and
// leaves out only the visibility and the MIS weight, both factors of g. MIS weighs the kept sample
// with the technique's own density p, as a BSDF sample weighs its direction: the two weights still
// sum to one at every direction, which is all the combination needs.
#ifndef ETK_LIGHT_RESAMPLING_H
#define ETK_LIGHT_RESAMPLING_H
#include "bsdf.h"
#include "color.h"
#include "compat.h"
#include "light_sampling.h"
#include "mis.h"
#include "params.h"
#include "sampler.h"
#include "surface.h"

ETK_BEGIN

// The sample pair a vertex at `depth` picks its candidate with (integrator.h's pair layout).
#define ETK_PAIR_RESAMPLE 0x48000000u

// The number of candidates of a vertex at `depth`: 1 (no resampling) where the technique is not
// the map's or the compensated map's (the learned tables sample their own product).
ETK_FN uint etk_light_candidates(EtkParams p, EtkLightSource src, int depth) {
    if (src.kind != ETK_LIGHT_MAP && src.kind != ETK_LIGHT_COMPENSATED)
        return 1u;
    int n = depth > 0 ? p.light_candidates_deeper : p.light_candidates_first;
    return n > 1 ? (uint)n : 1u;
}

// A kept light sample: the direction as the technique drew it, the BSDF's value and the map's
// radiance there, the direction in the shading frame, its MIS weight, and the weight that
// replaces 1 / p in the estimate (0: none kept).
typedef struct {
    EtkEnvSample ls;
    float3 wi, f, L;
    float mis, weight;
} EtkResampledLight;

// One candidate's target: luminance(f L) |cos| times its MIS weight against the continuation (lc,
// bc: the vertex's expected light and BSDF sample counts, integrator.h), the share of the
// integrand the light sample is there to estimate; and its BSDF value, radiance, local direction
// and MIS weight.
ETK_FN float etk_candidate_target(EtkScene S, EtkParams p, EtkSurface s, EtkEnvSample ls, float lc,
                                  float bc, EtkResampledLight* c) {
    c->wi = etk_to_local(ls.dir, s.t, s.b, s.ns);
    if (!(ls.pdf > 0.0f) || !etk_light_side_ok(s.m, c->wi.z, dot(ls.dir, s.ng)))
        return 0.0f;
    c->f = etk_bsdf_eval(s.m, s.wo, c->wi);
    c->L = etk_light_radiance(S, p, ls.uv);
    c->mis = p.mis ? etk_light_sample_weight(p, lc, ls.pdf, bc * etk_bsdf_pdf(s.m, s.wo, c->wi))
                   : 1.0f;
    float t = etk_luma(c->f * c->L) * fabs(c->wi.z) * c->mis;
    return isfinite(t) && t > 0.0f ? t : 0.0f;
}

// n candidates (a power of two) around sample point u, one kept by the streaming choice: candidate
// j replaces the kept one with probability w_j / (w_0 + ... + w_j), on one uniform `pick`
// rescaled after every decision, so the choice costs no storage per candidate.
ETK_FN EtkResampledLight etk_light_resample(EtkScene S, EtkParams p, EtkLightSource src,
                                            EtkSurface s, float lc, float bc, float2 u, float pick,
                                            uint n) {
    EtkResampledLight r;
    r.weight = 0.0f;
    float sum = 0.0f, kept_target = 0.0f;
    float2 unused;
    for (uint j = 0u; j < n; ++j) {
        EtkResampledLight c;
        c.ls = etk_light_sample(S, p, src, s, etk_lattice_point(u, j, n), &unused);
        float t = etk_candidate_target(S, p, s, c.ls, lc, bc, &c);
        if (!(t > 0.0f))
            continue;
        float w = t / c.ls.pdf;
        sum += w;
        float share = w / sum;
        if (pick < share) {
            pick = pick / share;
            r = c;
            kept_target = t;
        } else {
            pick = (pick - share) / (1.0f - share);
        }
    }
    r.weight = kept_target > 0.0f && isfinite(sum) ? sum / ((float)n * kept_target) : 0.0f;
    return r;
}

ETK_END

#endif
