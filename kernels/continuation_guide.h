// Path guiding of the continuation (the visibility strategy; issue 11). In a room lit through
// windows most of the light a wall receives comes from the sunlit patch on the floor, which a
// diffuse BSDF sample finds by chance. The visibility strategy's hash-grid cells
// (visibility_guide.h) also hold a distribution over ETK_GUIDE_REGIONS equal-area regions of the
// sphere of directions (ETK_GUIDE_ROWS bands of the world's y, ETK_GUIDE_COLS sectors of its
// azimuth), learned from the radiance that earlier continuation rays brought back to the cell
// (host/lib/render/visibility_cache.h), and the share c of continuation samples drawn from it.
// At a diffuse vertex the continuation is drawn from the one-sample mixture
//   p(w) = c p_guide(w) + (1 - c) p_bsdf(w),   p_guide(w) = P(R(w)) K / (4 pi),
// and weighted f cos / p(w): unbiased wherever the BSDF sample reaches (c < 1). The same p(w)
// is the BSDF technique's density in the MIS weights of the light sample and of an escaped ray.
// The mixture is sampled by inversion (u.x < c: the guide, else the BSDF, u.x rescaled), the
// region by inverting the cell's CDF as the light sample's regions are (etk_guide_pick_region),
// then uniformly in the region's solid angle.
#ifndef ETK_CONTINUATION_GUIDE_H
#define ETK_CONTINUATION_GUIDE_H
#include "bsdf.h"
#include "compat.h"
#include "latlong.h"
#include "params.h"
#include "path_state.h"
#include "trig.h"
#include "visibility_guide.h"

ETK_BEGIN

// The equal-area region of world direction d (unit): the band of its y (cos of the colatitude),
// the sector of its longitude u (latlong.h's, so the sectors are the map's column bands).
ETK_FN int etk_cguide_region(float3 d) {
    int band = (int)floor((1.0f - d.y) * (0.5f * ETK_GUIDE_ROWS));
    int col = (int)floor(etk_latlong_u(d) * ETK_GUIDE_COLS);
    return clamp(band, 0, ETK_GUIDE_ROWS - 1) * ETK_GUIDE_COLS + clamp(col, 0, ETK_GUIDE_COLS - 1);
}

// A direction uniformly in region R's solid angle from t in [0,1)^2: y uniform in the band (the
// sphere's area is uniform in y), u uniform in the sector. The band's top and the offset into it
// are summed last, so that t < 1 stays inside the band.
ETK_FN float3 etk_cguide_region_dir(int R, float2 t) {
    int band = R / ETK_GUIDE_COLS, col = R % ETK_GUIDE_COLS;
    float h = 2.0f / ETK_GUIDE_ROWS;
    float y = (1.0f - h * (float)band) - h * t.y;
    float u = ((float)col + t.x) * (1.0f / ETK_GUIDE_COLS);
    return etk_latlong_dir(u, y, sqrt(fmax(0.0f, 1.0f - y * y)));
}

// The cell's directional CDF (K + 1 entries), followed by its guided share.
ETK_FN ETK_GLOBAL const float* etk_cguide_cdf(EtkScene S, EtkParams p, int cell) {
    return S.guide_cells + etk_guide_dir_offset(p.guide_slots, cell);
}
// The share c of continuation samples a vertex of material m in `cell` draws from the guide: 0
// where the option is off or the material is not diffuse (only a diffuse BSDF sample reaches the
// whole hemisphere and has a lobe the guide's coarse regions can match). The caller asks only
// for the visibility strategy's vertices below the last bounce (etk_shade).
ETK_FN float etk_cguide_share(EtkScene S, EtkParams p, int cell, EtkMaterial m) {
    return p.guide_continuation && m.type == ETK_MAT_DIFFUSE
               ? etk_cguide_cdf(S, p, cell)[ETK_GUIDE_DIR_SHARE]
               : 0.0f;
}

// p_guide of world direction d (unit) in `cell`.
ETK_FN float etk_cguide_pdf(EtkScene S, EtkParams p, int cell, float3 d) {
    ETK_GLOBAL const float* cdf = etk_cguide_cdf(S, p, cell);
    int R = etk_cguide_region(d);
    return (cdf[R + 1] - cdf[R]) * (ETK_GUIDE_REGIONS * 0.25f * ETK_INV_PI);
}

// The mixture's density c p_guide + (1 - c) p_bsdf of world direction d.
ETK_FN float etk_cguide_mix_pdf(EtkScene S, EtkParams p, int cell, float c, float pdf_bsdf,
                                float3 d) {
    return c > 0.0f ? c * etk_cguide_pdf(S, p, cell, d) + (1.0f - c) * pdf_bsdf : pdf_bsdf;
}

// A direction from the guide of `cell`, from u in [0,1)^2.
ETK_FN float3 etk_cguide_sample(EtkScene S, EtkParams p, int cell, float2 u) {
    float2 t;
    int R = etk_guide_pick_region(etk_cguide_cdf(S, p, cell), u, &t);
    return etk_cguide_region_dir(R, t);
}

// A continuation drawn from the mixture at a vertex with shading frame (t, b, n): the guide with
// probability c (u.x < c), else the BSDF, u.x rescaled either way. pdf: the mixture's density
// of the direction, pdf_bsdf the BSDF's (both 0: no sample).
typedef struct {
    float3 wi_world, wi; // the direction in the world and in the shading frame
    float pdf, pdf_bsdf;
} EtkGuidedSample;

ETK_FN EtkGuidedSample etk_cguide_sample_mixture(EtkScene S, EtkParams p, int cell, float c,
                                                 EtkMaterial m, float3 wo, float3 t, float3 b,
                                                 float3 n, float2 u, float lobe) {
    EtkGuidedSample g;
    g.pdf = 0.0f;
    g.pdf_bsdf = 0.0f;
    if (u.x < c) {
        g.wi_world =
            etk_cguide_sample(S, p, cell, make_float2(etk_guide_rescale(u.x, 0.0f, c), u.y));
        g.wi = etk_to_local(g.wi_world, t, b, n);
        g.pdf_bsdf = etk_bsdf_pdf(m, wo, g.wi);
    } else {
        EtkBsdfSample bs =
            etk_bsdf_sample(m, wo, make_float2(etk_guide_rescale(u.x, c, 1.0f), u.y), lobe);
        g.wi = bs.wi;
        g.wi_world = etk_from_local(bs.wi, t, b, n);
        if (!(bs.pdf > 0.0f))
            return g;
        g.pdf_bsdf = bs.pdf;
    }
    g.pdf = etk_cguide_mix_pdf(S, p, cell, c, g.pdf_bsdf, g.wi_world);
    return g;
}

ETK_END

#endif
