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
#define ETK_HEURISTIC_BALANCE 0
#define ETK_HEURISTIC_POWER 1

ETK_BEGIN

// The strategies that draw one light and one BSDF sample and weight them by MIS.
ETK_FN int etk_strategy_is_mis(int strategy) {
    return strategy == ETK_STRATEGY_MIS || strategy == ETK_STRATEGY_COMPENSATED;
}

// 4-byte members only: passed by value to kernels, so host and device layouts agree.
typedef struct {
    EtkEnvMap env;
    float eye[3], forward[3], right[3], up[3]; // right/up scaled by the field of view
    int width, height;
    int max_depth, rr_depth;
    int strategy, heuristic;
    int sampler;
    uint seed;
    uint sample_index; // the pass: which sample of each pixel
    int first_pixel;   // pixel of slot 0 in this wave
    float ray_epsilon; // offset of secondary ray origins, relative to the coordinates' magnitude
    int light_count;   // directional lights or SIS strata (EtkScene.lights)
    int strata_width, strata_height; // SIS: the texel grid of the strata
    int bsdf_sampling; // GGX lobes: 1 visible normals, 0 the distribution of normals (bsdf.h)
    int pad;
} EtkParams;

ETK_END

#endif
