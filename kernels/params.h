// The per-pass parameters every stage takes by value, and the codes of the typed settings they
// carry (host/lib/render/settings.h names them).
#ifndef ETK_PARAMS_H
#define ETK_PARAMS_H
#include "compat.h"
#include "envmap.h"

// How a surface point is lit (the light sample of the shade stages).
#define ETK_STRATEGY_LIGHT 0       // one environment-map sample
#define ETK_STRATEGY_BSDF 1        // BSDF samples only
#define ETK_STRATEGY_MIS 2         // one of each, combined by multiple importance sampling
#define ETK_STRATEGY_UNIFORM 3     // uniform sphere directions (the baseline)
#define ETK_STRATEGY_SIS 4         // structured importance sampling: one stratum per sample
#define ETK_STRATEGY_LIGHTS 5      // a directional light set, all lights at every hit
#define ETK_STRATEGY_COMPENSATED 6 // MIS with the compensated map distribution (env_dist_comp)
#define ETK_STRATEGY_ADAPTIVE 7    // compensated map, light/BSDF share learned per material bin
// MIS, light samples and diffuse continuations guided by tables learned in the first passes.
#define ETK_STRATEGY_VISIBILITY 8
// MIS, light samples from the map times the cosine to the vertex's normal bin (normal_bins.h).
#define ETK_STRATEGY_COSINE 9
#define ETK_HEURISTIC_BALANCE 0
#define ETK_HEURISTIC_POWER 1
#define ETK_MAX_SPLIT 64 // light and BSDF samples per vertex, at most
// Material bins of the adaptive strategy's light shares (host/lib/render/light_share.h).
#define ETK_SHARE_BINS 32

ETK_BEGIN

// The strategies that draw one light and one BSDF sample and weight them by MIS.
ETK_FN int etk_strategy_is_mis(int strategy) {
    return strategy == ETK_STRATEGY_MIS || strategy == ETK_STRATEGY_COMPENSATED ||
           strategy == ETK_STRATEGY_VISIBILITY || strategy == ETK_STRATEGY_COSINE;
}

// Adaptive strategy: how a material bin samples, as flags beside its light share.
#define ETK_BIN_COMPENSATED 1 // light samples from the compensated distribution (else the full)
#define ETK_BIN_VNDF 2        // GGX lobes sampled from visible normals (else D(h) cos)
// Learning passes: every pixel renders with one of ETK_SHARE_CANDIDATES configurations, picked
// by a hash of the pixel and seed, so that the host can compare their variance per material
// (host/lib/render/light_share.h). Candidate 0 is the paper's estimator.
#define ETK_SHARE_CANDIDATES 4
ETK_FN int etk_learning_candidate(uint seed, int pixel) {
    uint x = (uint)pixel * 0x9e3779b9u ^ seed * 0x85ebca6bu;
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    return (int)(x % (uint)ETK_SHARE_CANDIDATES);
}
// Candidate k: (share, flags). 0: full distribution, s = 1, D(h) cos sampling (the paper's
// MIS); 1: the same with visible normals; 2: compensated, s = 1 (the compensated strategy);
// 3: compensated, s = 0.5 (more BSDF samples).
ETK_FN float etk_learning_share(int k, int last) {
    (void)last;
    return k == 3 ? 0.5f : 1.0f;
}
ETK_FN int etk_learning_flags(int k) {
    return k == 0 ? 0 : (k == 2 || k == 3) ? ETK_BIN_COMPENSATED | ETK_BIN_VNDF : ETK_BIN_VNDF;
}

// 4-byte members only: passed by value to kernels, so host and device layouts agree.
typedef struct {
    EtkEnvMap env;
    // right/up scaled by the field of view. Four floats each, the fourth 0: a compiler may load a
    // float3 as four floats, and the fourth of up[3] was the int `width`, whose bits read as a
    // float are a denormal -- every product in that lane then took a microcode assist (PoCL's
    // generate stage ran 3x slower for it, issue 12). No int's bits in a float lane.
    float eye[4], forward[4], right[4], up[4];
    int width, height;
    int max_depth;
    int rr_depth; // Russian roulette ends paths only past this many surfaces (integrator.h)
    int strategy, heuristic;
    int sampler;
    uint seed;
    uint sample_index; // the pass: which sample of each pixel
    int first_pixel;   // pixel of slot 0 in this wave
    float ray_epsilon; // offset of secondary ray origins, relative to the hit triangle's largest
                       // vertex coordinate (surface.h)
    int light_count;   // directional lights or SIS strata (EtkScene.lights)
    int strata_width, strata_height; // SIS: the texel grid of the strata
    int bsdf_sampling; // GGX lobes: 1 visible normals, 0 the distribution of normals (bsdf.h)
    int learn;         // adaptive: a learning pass (shares per pixel: etk_learning_share)
    // Adaptive: expected light samples (of the two at a vertex) per material bin, in [0, 2),
    // and how the bin samples (ETK_BIN_*).
    float light_share[ETK_SHARE_BINS];
    int bin_flags[ETK_SHARE_BINS];
    // Visibility strategy (kernels/visibility_guide.h): the hash grid over surface positions
    // (origin, 1 / cell size, slots: a power of two), whether the cells' tables hold anything
    // learned yet (they hold the map's defensive share too), and whether this pass records
    // shadow-ray outcomes; whether diffuse vertices guide their continuation too
    // (kernels/continuation_guide.h).
    float guide_origin[3];
    float guide_inv_cell;
    int guide_slots;
    int guide_ready;
    int guide_learn; // records shadow rays' and continuations' outcomes (visibility_cache.h)
    int guide_continuation;
    // Splitting (the mis strategy): light and BSDF samples per non-delta vertex, powers of two;
    // 1 and 1 are the paper's estimator (etk_split_samples in integrator.h).
    int light_samples, bsdf_samples;
    // The sample_lights stage has drawn the shade queue's light samples
    // (etk_batches_light_samples).
    int light_batch;
} EtkParams;

// Strategies whose light sample is one etk_env_sample at every vertex (the cosine strategy's, at a
// path's first vertex, one of its bin's table): the sample_lights stage can draw them ahead of the
// shade stage, in batches (integrator.h).
ETK_FN int etk_batches_light_samples(int strategy) {
    return strategy == ETK_STRATEGY_LIGHT || strategy == ETK_STRATEGY_MIS ||
           strategy == ETK_STRATEGY_COMPENSATED || strategy == ETK_STRATEGY_COSINE;
}

// Whether a vertex at `depth` (surface interactions before it) is the path's last: its
// continuation can only escape (integrator.h; the continuation guide's recorder, schedule.cpp).
ETK_FN int etk_last_bounce(EtkParams p, int depth) {
    return depth + 1 >= p.max_depth;
}

ETK_END

#endif
