// The per-pass parameters every stage takes by value, and the codes of the switches they carry
// (host/lib/prepare/technique.h resolves a strategy's name into them).
#ifndef ETK_PARAMS_H
#define ETK_PARAMS_H
#include "compat.h"
#include "envmap.h"

// Where a vertex's light sample comes from (EtkParams.light_first, light_deeper): one
// environment-sampling technique each, all behind one module (light_sampling.h). The host
// resolves a strategy name into these and the switches below (host/lib/prepare/technique.cpp).
#define ETK_LIGHT_NONE 0        // no light sample: BSDF samples alone
#define ETK_LIGHT_MAP 1         // the map's own distribution (env_dist): the paper's
#define ETK_LIGHT_COMPENSATED 2 // its MIS-compensated twin (env_dist_comp; env_compensation.h)
#define ETK_LIGHT_BINNED 3      // the map times a cosine bound of the vertex's normal bin
#define ETK_LIGHT_LEARNED 4     // the visibility tables of the vertex's hash-grid cell
#define ETK_LIGHT_UNIFORM 5     // uniform directions on the sphere (the baseline)
#define ETK_LIGHT_STRATA 6      // SIS: one stratum of the map per sample, direct light only
#define ETK_LIGHT_SET 7         // a directional light set, every light at every hit
#define ETK_HEURISTIC_BALANCE 0
#define ETK_HEURISTIC_POWER 1
#define ETK_MAX_SPLIT 64 // light and BSDF samples per vertex, at most

ETK_BEGIN

// 4-byte members only: passed by value to kernels, so host and device layouts agree.
typedef struct {
    EtkEnvMap env;
    // right/up scaled by the field of view. Four floats each, the fourth 0: a compiler may load a
    // float3 as four floats, and the fourth of up[3] was the int `width`, whose bits read as a
    // float are a denormal -- every product in that lane then took a microcode assist (PoCL's
    // generate stage ran 3x slower for it). No int's bits in a float lane.
    float eye[4], forward[4], right[4], up[4];
    int width, height;
    int max_depth;
    int rr_depth; // Russian roulette ends paths only past this many surfaces (integrator.h)
    // The light sample's technique at a path's first vertex and below it (ETK_LIGHT_*).
    int light_first, light_deeper;
    // 1: light and BSDF samples are combined by multiple importance sampling (weights by
    // `heuristic`); 0: each technique counts alone -- a light sample in full, an escaped
    // continuation only where no light sample was drawn.
    int mis;
    int heuristic;
    // 1: a vertex continues its path; 0: direct light only (SIS).
    int continuation;
    // 1: at a path's last vertex the BSDF sample is taken only with the probability its lobe
    // can reach the map's light (etk_last_bsdf_share).
    int thin_last_bsdf;
    int sampler;
    uint seed;
    uint sample_index; // the pass: which sample of each pixel
    int first_pixel;   // pixel of slot 0 in this wave
    int pixel_stride;  // pixels between slots: 1, or a measuring pass's subset (schedule.h)
    float ray_epsilon; // offset of secondary ray origins, relative to the hit triangle's largest
                       // vertex coordinate (surface.h)
    int light_count;   // directional lights or SIS strata (EtkScene.lights)
    int strata_width, strata_height; // SIS: the texel grid of the strata
    int bsdf_sampling; // GGX lobes: 1 visible normals, 0 the distribution of normals (bsdf.h)
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
    float guide_inv_power; // 1 / the map's power: the unit of the records (visibility_record.h)
    float guide_continuation_share; // a well-learned cell's guided share (VisibilityOptions)
    // The binned technique's first table in guide_cells (cosine_light.h), in tables of
    // ETK_GUIDE_CELL_FLOATS: 0 for the cosine strategy; after the learned tables where auto's
    // verdict measures the binned technique beside them (VisibilityOptions::alternative).
    int bin_cell_base;
    // Splitting (the mis strategy): light and BSDF samples per non-delta vertex, powers of two;
    // 1 and 1 are the paper's estimator (etk_split_samples in integrator.h).
    int light_samples, bsdf_samples;
    // The sample_lights stage has drawn the shade queue's light samples (etk_light_batches:
    // both techniques must allow it).
    int light_batch;
} EtkParams;

// Whether a vertex at `depth` (surface interactions before it) is the path's last: its
// continuation can only escape (integrator.h; the continuation guide's recorder, schedule.cpp).
ETK_FN int etk_last_bounce(EtkParams p, int depth) {
    return depth + 1 >= p.max_depth;
}

ETK_END

#endif
