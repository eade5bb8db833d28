// The light-sampling module: which distribution a vertex's light sample is drawn from, a sample
// of it, its density of any direction, and the map's radiance there -- the one place the shade
// stage, the batched light stage (sample_lights), splitting and escaped rays all ask, so that a
// light sample and the MIS weight of a BSDF sample that reaches the same direction always agree
// (as pbrt-v4's ImageInfiniteLight::SampleLi / PDF_Li with allowIncompletePDF, or Cycles'
// light/sample.h). Each technique (ETK_LIGHT_* in params.h) keeps its tables and maths in a file
// of its own: envmap.h (map, compensated), cosine_light.h (binned), visibility_guide.h and
// portal_guide.h (learned); adding one is a case in each function below
// (docs/architecture.md#adding-a-technique).
#ifndef ETK_LIGHT_SAMPLING_H
#define ETK_LIGHT_SAMPLING_H
#include "bsdf.h"
#include "compat.h"
#include "cosine_light.h"
#include "envmap.h"
#include "params.h"
#include "path_state.h"
#include "portal_guide.h"
#include "surface.h"
#include "visibility_guide.h"

ETK_BEGIN

// The distribution of one vertex's light sample: its technique and, for the binned and learned
// ones, the table's cell (a normal bin; a hash-grid cell).
typedef struct {
    int kind; // ETK_LIGHT_*
    int cell;
} EtkLightSource;

// The technique of a vertex at `depth` (surface interactions before it).
ETK_FN int etk_light_kind(EtkParams p, int depth) {
    return depth > 0 ? p.light_deeper : p.light_first;
}

// The source of a vertex at `depth` whose cell is `cell` (etk_light_cell). A binned vertex
// without a bin (a dielectric) takes the full map.
ETK_FN EtkLightSource etk_light_source(EtkParams p, int depth, int cell) {
    EtkLightSource src;
    src.kind = etk_light_kind(p, depth);
    src.cell = cell;
    if (src.kind == ETK_LIGHT_BINNED && cell < 0)
        src.kind = ETK_LIGHT_MAP;
    return src;
}

// The cell of surface s (material m) for the technique `kind`; 0 where it has none.
ETK_FN int etk_light_cell(EtkParams p, int kind, EtkSurface s, EtkMaterial m) {
    return kind == ETK_LIGHT_LEARNED  ? etk_guide_cell(p, s.origin, s.ng)
           : kind == ETK_LIGHT_BINNED ? etk_cosine_cell(p, m, s.ns)
                                      : 0;
}

// Whether the sample_lights stage can draw the technique's samples ahead of the shade stage, in
// batches: one sample each, from tables that depend on nothing but the vertex's bin or cell (and,
// for the learned portals, its ray start, which the batch finds from the hit).
ETK_FN int etk_light_batches(int kind) {
    return kind == ETK_LIGHT_MAP || kind == ETK_LIGHT_COMPENSATED || kind == ETK_LIGHT_BINNED ||
           kind == ETK_LIGHT_LEARNED;
}

// The 2D table of the map-shaped techniques: the compensated one's, or the map's own.
ETK_FN ETK_GLOBAL const float* etk_light_table(EtkScene S, int kind) {
    return kind == ETK_LIGHT_COMPENSATED ? S.env_dist_comp : S.env_dist;
}

// The expected number of light samples a vertex takes, in (0, 1]: below 1 where the learned
// tables found its light samples mostly blocked (etk_guide_light_count).
ETK_FN float etk_light_count(EtkScene S, EtkParams p, EtkLightSource src) {
    return src.kind == ETK_LIGHT_LEARNED ? etk_guide_light_count(S, p, src.cell) : 1.0f;
}

// A light sample at surface s from u in [0,1)^2: direction, map coordinates and density (0: no
// sample). *parts: the learned technique's two densities (portal_guide.h), for its learning.
ETK_STRUCT_INLINE_FN EtkEnvSample etk_light_sample(EtkScene S, EtkParams p, EtkLightSource src,
                                                   EtkSurface s, float2 u, float2* parts) {
    if (src.kind == ETK_LIGHT_LEARNED)
        return etk_guide_light_sample(S, p, src.cell, s, u, parts);
    if (src.kind == ETK_LIGHT_BINNED)
        return etk_guide_sample(S, p, src.cell, u);
    if (src.kind == ETK_LIGHT_UNIFORM) {
        EtkEnvSample r;
        r.dir = etk_sample_uniform_sphere(u);
        r.uv = etk_env_uv(p.env, r.dir);
        r.pdf = 0.25f * ETK_INV_PI;
        r.row = 0;
        r.col = 0;
        return r;
    }
    return etk_env_sample(etk_light_table(S, src.kind), p.env, u);
}

// The density etk_light_sample draws direction d (unit; map coordinates uv) with from a vertex
// whose rays start at o: what MIS weighs a BSDF sample in that direction against.
ETK_STRUCT_INLINE_FN float etk_light_pdf(EtkScene S, EtkParams p, EtkLightSource src, float3 o,
                                         float3 d, float2 uv) {
    if (src.kind == ETK_LIGHT_LEARNED)
        return etk_guide_light_pdf(S, p, src.cell, o, d, uv);
    if (src.kind == ETK_LIGHT_BINNED)
        return etk_cosine_light_pdf(S, p, src.cell, uv);
    if (src.kind == ETK_LIGHT_UNIFORM)
        return 0.25f * ETK_INV_PI;
    return etk_env_pdf_uv(etk_light_table(S, src.kind), p.env, uv);
}

// The map's radiance at map coordinates uv.
ETK_FN float3 etk_light_radiance(EtkScene S, EtkParams p, float2 uv) {
    return etk_env_radiance_uv(S.env_texels, p.env, uv);
}

// The light sample sample_lights drew for the path in `slot`: direction and density (its
// radiance is light_L; its map coordinates are not kept: nothing after reads them).
ETK_FN EtkEnvSample etk_drawn_light_sample(EtkPaths P, int slot) {
    float4 d = P.light_dir[slot];
    EtkEnvSample s;
    s.dir = etk_xyz(d);
    s.pdf = d.w;
    s.uv = make_float2(0.0f, 0.0f);
    s.row = 0;
    s.col = 0;
    return s;
}

ETK_END

#endif
