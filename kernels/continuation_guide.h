// Path guiding of the continuation (the visibility strategy). In a room lit through
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
//
// Secondary sources as points. The regions are 11.25 degrees wide and fixed to the cell, while the
// sunlit patch on a floor is a place: from across a cell it moves through several regions. So the
// guide's share is itself a mixture, (1 - q) p_guide + q p_spot, where p_spot is a second
// scene-wide table of the scene box's cells with portal_guide.h's layout and density (a cell, a
// point in it, the direction towards it: parallax exact), learned from where the continuations of
// the learning passes left the box with the light they brought back: where indirect light comes
// from, projected onto the box (exactly, where the source is on the box: a floor, a wall). q is
// chosen per hash-grid cell by the host (visibility_cache.h), 0 until the table holds something:
//   p(w) = c ((1 - q) p_guide(w) + q p_spot(w)) + (1 - c) p_bsdf(w).
#ifndef ETK_CONTINUATION_GUIDE_H
#define ETK_CONTINUATION_GUIDE_H
#include "bsdf.h"
#include "compat.h"
#include "latlong.h"
#include "params.h"
#include "path_state.h"
#include "portal_guide.h"
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

// p_guide of the directions in region R for a cell's directional CDF.
ETK_FN float etk_cguide_pdf_of_region(ETK_GLOBAL const float* cdf, int R) {
    return (cdf[R + 1] - cdf[R]) * (ETK_GUIDE_REGIONS * 0.25f * ETK_INV_PI);
}
// p_guide of world direction d (unit) for a cell's directional CDF (host and device).
ETK_FN float etk_cguide_region_pdf(ETK_GLOBAL const float* cdf, float3 d) {
    return etk_cguide_pdf_of_region(cdf, etk_cguide_region(d));
}
// p_guide of world direction d (unit) in `cell`.
ETK_FN float etk_cguide_pdf(EtkScene S, EtkParams p, int cell, float3 d) {
    return etk_cguide_region_pdf(etk_cguide_cdf(S, p, cell), d);
}

// The point table of secondary sources (after the portal table in guide_cells; the same
// layout, its per-slot entries the share q) and a vertex's q.
ETK_FORCE_INLINE_FN ETK_GLOBAL const float* etk_spot_table(EtkScene S, EtkParams p) {
    return etk_portal_table(S, p) + etk_portal_size(p.guide_slots);
}
ETK_FORCE_INLINE_FN float etk_spot_share(EtkScene S, EtkParams p, int cell) {
    ETK_GLOBAL const float* box = etk_spot_table(S, p);
    return box[ETK_PORTAL_ON] > 0.0f ? box[ETK_PORTAL_SHARES + cell] : 0.0f;
}

// The guided shares c a cell chooses among once it has learned (host/lib/render/
// visibility_cache.h): 0, 1/4, 1/2. Where light comes back by paths the guide misses (the sun
// through a mirror-like statue onto the ground under the open sky), a share c leaves them 1 - c of
// the BSDF's density and multiplies their weight by 1 / (1 - c): c = 0 wins there.
#define ETK_GUIDED_CANDIDATES 3
ETK_FN float etk_guided_candidate(int j) {
    return 0.25f * (float)j;
}

// The mixture's density from its parts (the host's learning evaluates candidate shares with it).
ETK_FN float etk_cguide_mix(float c, float q, float pg, float ps, float pb) {
    return c * ((1.0f - q) * pg + q * ps) + (1.0f - c) * pb;
}

// The mixture's density c ((1 - q) p_guide + q p_spot) + (1 - c) p_bsdf of world direction d
// (unit), whose ray starts at o (etk_surface_origin: the point the spot table's density is
// measured from).
ETK_FORCE_INLINE_FN float etk_cguide_mix_pdf(EtkScene S, EtkParams p, int cell, float c,
                                             float pdf_bsdf, float3 o, float3 d) {
    if (!(c > 0.0f))
        return pdf_bsdf;
    float q = etk_spot_share(S, p, cell);
    float ps = q > 0.0f ? etk_portal_pdf(etk_spot_table(S, p), o, d) : 0.0f;
    return etk_cguide_mix(c, q, etk_cguide_pdf(S, p, cell, d), ps, pdf_bsdf);
}

// A direction from the guide of `cell`, from u in [0,1)^2.
ETK_FN float3 etk_cguide_sample(EtkScene S, EtkParams p, int cell, float2 u) {
    float2 t;
    int R = etk_guide_pick_region(etk_cguide_cdf(S, p, cell), u, &t);
    return etk_cguide_region_dir(R, t);
}

// A continuation drawn from the mixture at surface s (shading frame t, b, n): the guide with
// probability c (u.x < c; within it the spot table's point with probability q), else the BSDF,
// u.x rescaled at each choice. pdf: the mixture's density of the direction, pdf_bsdf the BSDF's
// (both 0: no sample).
typedef struct {
    float3 wi_world, wi; // the direction in the world and in the shading frame
    float pdf, pdf_bsdf;
} EtkGuidedSample;

ETK_FN EtkGuidedSample etk_cguide_sample_mixture(EtkScene S, EtkParams p, int cell, float c,
                                                 EtkMaterial m, EtkSurface s, float3 t, float3 b,
                                                 float3 n, float2 u, float lobe) {
    EtkGuidedSample g;
    g.pdf = 0.0f;
    g.pdf_bsdf = 0.0f;
    float3 wo = s.wo;
    if (u.x < c) {
        float x = etk_guide_rescale(u.x, 0.0f, c), q = etk_spot_share(S, p, cell);
        g.wi_world =
            x < q ? etk_portal_sample_dir(etk_spot_table(S, p), etk_surface_start(s),
                                          make_float2(etk_guide_rescale(x, 0.0f, q), u.y))
                  : etk_cguide_sample(S, p, cell, make_float2(etk_guide_rescale(x, q, 1.0f), u.y));
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
    g.pdf = etk_cguide_mix_pdf(S, p, cell, c, g.pdf_bsdf, etk_surface_origin(s, g.wi_world),
                               g.wi_world);
    return g;
}

ETK_END

#endif
