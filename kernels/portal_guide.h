// Learned portals (the visibility strategy). In a room lit through windows the light
// that reaches a point comes through a few openings, and from across the room a window is a
// small solid angle that no fixed set of direction regions resolves (visibility_guide.h's are
// 11.25 degrees wide, a window seen from across the room crosses several, and their cells are
// 1/8 of the room wide, so the window's direction moves inside one). Where the light gets in is
// a property of the scene, not of the receiving point: every unoccluded shadow ray leaves the
// scene's (slightly enlarged) bounding box through the opening it passed. So the box's six faces
// are split into ETK_PORTAL_N x ETK_PORTAL_N cells each, and one table for the whole scene,
// learned from where the unoccluded shadow rays of the learning passes leave the box
// (host/lib/render/visibility_cache.h), is a distribution over those cells: in effect portals
// placed by the renderer itself. A point x samples it by choosing a cell, a point y uniformly
// in it, and the direction towards y; parallax is exact, because y is a point, not a direction.
// Its solid-angle density is
//   p_portal(w) = P(k) / A(k) x t^2 / |w . n_face|,
// k the cell where the ray from x along w leaves the box, t its distance there, A(k) the cell's
// area: the ray from a point inside the box leaves it exactly once, so every direction has one
// cell and the density integrates to one over the sphere.
// The light sample of the visibility strategy is then the one-sample mixture
//   p(w) = (1 - b) p_vis(w) + b p_portal(w),
// p_vis the hash-grid cell's mixture (visibility_guide.h), positive wherever the map is, so the
// estimator stays unbiased whatever the portal table holds; b is the table's share (0 until
// something is learned). It is drawn by inversion of u.x (below b: the portal, else the cell's
// mixture, u.x rescaled either way) and its density is evaluated the same way by the escaped
// stage for the BSDF sample's MIS weight, from the continuation's origin: the light sample's
// direction is aimed from that same point (the surface's origin on the direction's side).
//
// Table (etk_portal_size floats, after the cells' tables in guide_cells): the box's low and high
// corners, whether it is on, one unused float, then the CDF over the 6 N^2 cells (face f = 2 axis
// + (outward along +axis), then i along axis + 1, j along axis + 2, modulo 3), its guide table
// (piecewise_constant.h's cutpoints: a sample's cell in one or two reads of the CDF, where the
// binary search over 6,144 cells took 13 dependent ones and two thirds of the portal sample's
// time), then each hash-grid slot's share b.
#ifndef ETK_PORTAL_GUIDE_H
#define ETK_PORTAL_GUIDE_H
#include "compat.h"
#include "envmap.h"
#include "params.h"
#include "path_state.h"
#include "piecewise_constant.h"
#include "surface.h"
#include "visibility_guide.h"

#define ETK_PORTAL_N 32
#define ETK_PORTAL_CELLS (6 * ETK_PORTAL_N * ETK_PORTAL_N)
#define ETK_PORTAL_ON 6 // 1 once the table holds something learned
#define ETK_PORTAL_CDF 8
#define ETK_PORTAL_GUIDE (ETK_PORTAL_CDF + ETK_PORTAL_CELLS + 1)
#define ETK_PORTAL_GUIDE_CELLS 2048 // etk_guide_cells(ETK_PORTAL_CELLS)
#define ETK_PORTAL_SHARES (ETK_PORTAL_GUIDE + ETK_PORTAL_GUIDE_CELLS + 1)
// The shares b a hash-grid cell chooses among, by the least second moment of its light sample
// on its records (host/lib/render/visibility_cache.h): 0, 1/4, 1/2, 3/4.
#define ETK_PORTAL_CANDIDATES 4

ETK_BEGIN

// Where the portal table starts in guide_cells: after the light sample's and the continuation
// guide's halves (visibility_guide.h).
ETK_FN int etk_portal_offset(int slots, int continuation) {
    return slots * (ETK_GUIDE_CELL_FLOATS + (continuation ? ETK_GUIDE_DIR_FLOATS : 0));
}
ETK_FN ETK_GLOBAL const float* etk_portal_table(EtkScene S, EtkParams p) {
    return S.guide_cells + etk_portal_offset(p.guide_slots, p.guide_continuation);
}
// Floats of the portal table for `slots` hash-grid cells.
ETK_FN int etk_portal_size(int slots) {
    return ETK_PORTAL_SHARES + slots;
}
// The share b of light samples a vertex in hash-grid `cell` draws from the portal table.
ETK_FN float etk_portal_share(EtkScene S, EtkParams p, int cell) {
    ETK_GLOBAL const float* box = etk_portal_table(S, p);
    return p.guide_ready && box[ETK_PORTAL_ON] > 0.0f ? box[ETK_PORTAL_SHARES + cell] : 0.0f;
}

ETK_FN float etk_portal_candidate(int j) {
    return 0.25f * (float)j;
}

// Component a (0, 1, 2) of v: OpenCL C has no run-time component index.
ETK_FN float etk_portal_comp(float3 v, int a) {
    return a == 0 ? v.x : (a == 1 ? v.y : v.z);
}

// The cell where the ray from o (inside the box) along unit d leaves the box; *t: its distance.
ETK_FN int etk_portal_exit(ETK_GLOBAL const float* box, float3 o, float3 d, float* t) {
    float best = 3.0e38f;
    int axis = 0;
    for (int a = 0; a < 3; ++a) {
        float da = etk_portal_comp(d, a);
        float ta =
            da != 0.0f ? ((da > 0.0f ? box[3 + a] : box[a]) - etk_portal_comp(o, a)) / da : 3.0e38f;
        axis = ta < best ? a : axis;
        best = fmin(ta, best);
    }
    best = fmax(best, 0.0f);
    float3 y = o + d * best;
    int a1 = axis == 2 ? 0 : axis + 1, a2 = axis == 0 ? 2 : axis - 1;
    float f1 = (etk_portal_comp(y, a1) - box[a1]) / (box[3 + a1] - box[a1]);
    float f2 = (etk_portal_comp(y, a2) - box[a2]) / (box[3 + a2] - box[a2]);
    int i = clamp((int)floor(f1 * (float)ETK_PORTAL_N), 0, ETK_PORTAL_N - 1);
    int j = clamp((int)floor(f2 * (float)ETK_PORTAL_N), 0, ETK_PORTAL_N - 1);
    int face = 2 * axis + (etk_portal_comp(d, axis) > 0.0f ? 1 : 0);
    *t = best;
    return (face * ETK_PORTAL_N + i) * ETK_PORTAL_N + j;
}

// The area of a cell of face `face`.
ETK_FN float etk_portal_cell_area(ETK_GLOBAL const float* box, int face) {
    int axis = face / 2;
    int a1 = axis == 2 ? 0 : axis + 1, a2 = axis == 0 ? 2 : axis - 1;
    return (box[3 + a1] - box[a1]) * (box[3 + a2] - box[a2]) *
           (1.0f / (float)(ETK_PORTAL_N * ETK_PORTAL_N));
}

// p_portal of unit direction d whose ray leaves the box by cell k at distance t.
ETK_FN float etk_portal_pdf_exit(ETK_GLOBAL const float* box, float3 d, int k, float t) {
    int face = k / (ETK_PORTAL_N * ETK_PORTAL_N);
    float P = box[ETK_PORTAL_CDF + k + 1] - box[ETK_PORTAL_CDF + k];
    float c = fabs(etk_portal_comp(d, face / 2));
    return P > 0.0f && c > 0.0f ? P / etk_portal_cell_area(box, face) * (t * t / c) : 0.0f;
}

// p_portal of unit direction d from o.
ETK_FN float etk_portal_pdf(ETK_GLOBAL const float* box, float3 o, float3 d) {
    float t;
    int k = etk_portal_exit(box, o, d, &t);
    return etk_portal_pdf_exit(box, d, k, t);
}

// A point on the box's surface from u in [0,1)^2: the cell by inverting the table with u.x,
// then uniformly inside it (u.x rescaled across the cell's i, u.y across its j).
ETK_FN float3 etk_portal_point(ETK_GLOBAL const float* box, float2 u) {
    ETK_GLOBAL const float* cdf = box + ETK_PORTAL_CDF;
    int k = etk_find_interval_guided(cdf, ETK_PORTAL_CELLS, box + ETK_PORTAL_GUIDE, u.x);
    float fi = etk_guide_rescale(u.x, cdf[k], cdf[k + 1]);
    int face = k / (ETK_PORTAL_N * ETK_PORTAL_N), rest = k % (ETK_PORTAL_N * ETK_PORTAL_N);
    int i = rest / ETK_PORTAL_N, j = rest % ETK_PORTAL_N;
    int axis = face / 2;
    int a1 = axis == 2 ? 0 : axis + 1, a2 = axis == 0 ? 2 : axis - 1;
    float plane = (face & 1) ? box[3 + axis] : box[axis];
    float c1 = box[a1] + ((float)i + fi) * (1.0f / ETK_PORTAL_N) * (box[3 + a1] - box[a1]);
    float c2 = box[a2] + ((float)j + u.y) * (1.0f / ETK_PORTAL_N) * (box[3 + a2] - box[a2]);
    float x = axis == 0 ? plane : (a1 == 0 ? c1 : c2);
    float y = axis == 1 ? plane : (a1 == 1 ? c1 : c2);
    float z = axis == 2 ? plane : (a1 == 2 ? c1 : c2);
    return make_float3(x, y, z);
}

// The direction from a surface (its ray start r) towards a point drawn from the table: aimed from
// the surface's origin on the side it leaves by (the origin its shadow ray, or its continuation,
// starts from).
ETK_FN float3 etk_portal_dir_to(EtkRayStart r, float3 y) {
    return normalize(y - etk_start_towards(r, normalize(y - r.origin)));
}
ETK_STRUCT_INLINE_FN float3 etk_portal_sample_dir(ETK_GLOBAL const float* box, EtkRayStart r,
                                                  float2 u) {
    return etk_portal_dir_to(r, etk_portal_point(box, u));
}

// The whole mixture's density from its parts' densities pv and pp and the portal share b.
ETK_FN float etk_portal_mix(float b, float pv, float pp) {
    return b > 0.0f ? (1.0f - b) * pv + b * pp : pv;
}

// The light sample's density at a vertex in hash-grid `cell` whose ray towards d (unit; map
// coordinates uv) starts at o: the cell's mixture, and the portal table's share of it.
ETK_FN float etk_guide_light_pdf(EtkScene S, EtkParams p, int cell, float3 o, float3 d, float2 uv) {
    float pv = etk_guide_pdf_uv(S, p, cell, uv);
    float b = etk_portal_share(S, p, cell);
    return b > 0.0f ? etk_portal_mix(b, pv, etk_portal_pdf(etk_portal_table(S, p), o, d)) : pv;
}

// The visibility strategy's light sample is drawn in two steps, which the batch below shares:
// the direction from one part of the mixture, then the whole mixture's density.
// The portal part's direction from ray start r (u.x already below the share b, rescaled) and its
// map coordinates.
ETK_STRUCT_INLINE_FN EtkEnvSample etk_portal_light_dir(EtkScene S, EtkParams p, EtkRayStart r,
                                                       float2 u) {
    EtkEnvSample e;
    e.dir = etk_portal_sample_dir(etk_portal_table(S, p), r, u);
    e.uv = etk_env_uv(p.env, e.dir);
    e.row = etk_cell_of(e.uv.y, p.env.dist_h);
    e.col = etk_cell_of(e.uv.x, p.env.dist_w);
    e.pdf = 0.0f; // the mixture's, below
    return e;
}
// The mixture's density of direction d from ray start r, given the cell's mixture's density pv
// and the portal share b; *parts: p_vis and p_portal (the latter only while learning or where
// b > 0), for the learning's choice of b.
ETK_FN float etk_guide_light_mix(EtkParams p, ETK_GLOBAL const float* box, float b, EtkRayStart r,
                                 float3 d, float pv, float2* parts) {
    float pp = b > 0.0f || p.guide_learn ? etk_portal_pdf(box, etk_start_towards(r, d), d) : 0.0f;
    *parts = make_float2(pv, pp);
    return etk_portal_mix(b, pv, pp);
}

// Which part of the mixture u in [0,1)^2 draws from at portal share b: the portal table's (1)
// where u.x < b, else the cell's tables (0); *t: u with u.x rescaled into that part.
ETK_FN int etk_guide_light_part(float b, float2 u, float2* t) {
    int portal = b > 0.0f && u.x < b;
    *t = portal ? make_float2(etk_guide_rescale(u.x, 0.0f, b), u.y)
                : (b > 0.0f ? make_float2(etk_guide_rescale(u.x, b, 1.0f), u.y) : u);
    return portal;
}

// The visibility strategy's light sample at surface s in `cell`, from u in [0,1)^2: with
// probability b (u.x < b) towards the portal table's point, else the cell's mixture
// (etk_guide_sample); pdf: the whole mixture's.
ETK_FN EtkEnvSample etk_guide_light_sample(EtkScene S, EtkParams p, int cell, EtkSurface s,
                                           float2 u, float2* parts) {
    float b = etk_portal_share(S, p, cell);
    EtkRayStart start = etk_surface_start(s);
    EtkEnvSample r;
    float pv;
    float2 t;
    if (etk_guide_light_part(b, u, &t)) {
        r = etk_portal_light_dir(S, p, start, t);
        pv = etk_guide_pdf_uv(S, p, cell, r.uv);
    } else {
        r = etk_guide_sample(S, p, cell, t);
        pv = r.pdf;
    }
    r.pdf = etk_guide_light_mix(p, etk_portal_table(S, p), b, start, r.dir, pv, parts);
    return r;
}

// The portal part's samples of a batch (etk_portal_light_dir's), in two loops over the batch's
// arrays: the points, then the directions towards them and their map coordinates. Short loops let
// the samples' table reads and long dependency chains (two normalisations, two arctangents)
// overlap, where drawn inside the loop that also finds each sample's surface and cell they ran
// one after another (sample_lights about 0.9x in rooms). Sample portal[j] from (px[j], py[j]),
// from ray start start[portal[j]], into entry portal[j] of the arrays, its density 0 (the
// mixture's, later).
ETK_FN void etk_portal_dir_batch(EtkScene S, EtkParams p, const EtkRayStart* start,
                                 const int* portal, const float* px, const float* py, int np,
                                 float* u, float* v, float* dx, float* dy, float* dz, float* pdf) {
    ETK_GLOBAL const float* box = etk_portal_table(S, p);
    float yx[ETK_LIGHT_BATCH], yy[ETK_LIGHT_BATCH], yz[ETK_LIGHT_BATCH];
    for (int j = 0; j < np; ++j) {
        float3 y = etk_portal_point(box, make_float2(px[j], py[j]));
        yx[j] = y.x;
        yy[j] = y.y;
        yz[j] = y.z;
    }
    for (int j = 0; j < np; ++j) {
        int k = portal[j];
        float3 d = etk_portal_dir_to(start[k], make_float3(yx[j], yy[j], yz[j]));
        float2 uv = etk_env_uv(p.env, d);
        u[k] = uv.x;
        v[k] = uv.y;
        dx[k] = d.x;
        dy[k] = d.y;
        dz[k] = d.z;
        pdf[k] = 0.0f;
    }
}

// The learned light samples of the paths in slots[0 .. n-1] (n <= ETK_LIGHT_BATCH) from (xu[k],
// xv[k]), as etk_guide_light_sample draws them, into light_dir, light_L and light_cell, and while
// learning the record's key and parts into shadow_key and guide_parts (the shade stage pushes them
// with the shadow ray; the last bounce's records were taken before this stage). The samples of
// the cells' tables in steps across the batch (etk_guide_table_batch), gathered into a batch of
// their own, and the portal's (etk_portal_dir_batch); every sample before the first tables one
// at a time.
ETK_FN void etk_guide_light_batch(EtkScene S, EtkPaths P, EtkParams p, ETK_GLOBAL const int* slots,
                                  const float* xu, const float* xv, int n) {
    ETK_GLOBAL const float* box = etk_portal_table(S, p);
    EtkRayStart start[ETK_LIGHT_BATCH];
    int cell[ETK_LIGHT_BATCH], item[ETK_LIGHT_BATCH], tcell[ETK_LIGHT_BATCH],
        portal[ETK_LIGHT_BATCH];
    float b[ETK_LIGHT_BATCH], u[ETK_LIGHT_BATCH], v[ETK_LIGHT_BATCH], pdf[ETK_LIGHT_BATCH];
    float dx[ETK_LIGHT_BATCH], dy[ETK_LIGHT_BATCH], dz[ETK_LIGHT_BATCH];
    float tx[ETK_LIGHT_BATCH], ty[ETK_LIGHT_BATCH]; // the table samples' values
    float px[ETK_LIGHT_BATCH], py[ETK_LIGHT_BATCH]; // the portal samples'
    int m = 0, np = 0;                              // table samples, portal samples
    // Each sample's surface and cell, its share, its part of the mixture: three loops, so that the
    // shares' cache misses overlap.
    for (int k = 0; k < n; ++k) {
        start[k] = etk_path_start(S, P, p, slots[k]);
        cell[k] = etk_guide_cell(p, start[k].origin, start[k].ng);
    }
    for (int k = 0; k < n; ++k)
        b[k] = etk_portal_share(S, p, cell[k]);
    for (int k = 0; k < n; ++k) {
        float2 t;
        if (etk_guide_light_part(b[k], make_float2(xu[k], xv[k]), &t)) {
            px[np] = t.x;
            py[np] = t.y;
            portal[np++] = k;
        } else {
            item[m] = k;
            tcell[m] = cell[k];
            tx[m] = t.x;
            ty[m] = t.y;
            ++m;
        }
    }
    etk_portal_dir_batch(S, p, start, portal, px, py, np, u, v, dx, dy, dz, pdf);
    for (int j = 0; j < np; ++j) // the portal samples' densities, their misses overlapping
        etk_guide_pdf_prefetch(S, p, cell[portal[j]], make_float2(u[portal[j]], v[portal[j]]));
    for (int j = 0; j < np; ++j) {
        int k = portal[j];
        pdf[k] = etk_guide_pdf_uv(S, p, cell[k], make_float2(u[k], v[k]));
    }
    float tu[ETK_LIGHT_BATCH], tv[ETK_LIGHT_BATCH], tdx[ETK_LIGHT_BATCH], tdy[ETK_LIGHT_BATCH];
    float tdz[ETK_LIGHT_BATCH], tpdf[ETK_LIGHT_BATCH];
    if (p.guide_ready) {
        etk_guide_table_batch(S, p, tcell, tx, ty, m, tu, tv, tdx, tdy, tdz, tpdf);
    } else { // etk_guide_sample's map samples (no portal share before the tables either)
        for (int j = 0; j < m; ++j)
            etk_batch_put(etk_env_sample(S.env_dist, p.env, make_float2(tx[j], ty[j])), j, tu, tv,
                          tdx, tdy, tdz, tpdf);
    }
    for (int j = 0; j < m; ++j) {
        int k = item[j];
        u[k] = tu[j];
        v[k] = tv[j];
        dx[k] = tdx[j];
        dy[k] = tdy[j];
        dz[k] = tdz[j];
        pdf[k] = tpdf[j];
    }
    // Every sample's whole mixture density; while learning, its record's key and parts.
    for (int k = 0; k < n; ++k) {
        float2 parts;
        pdf[k] = etk_guide_light_mix(p, box, b[k], start[k], make_float3(dx[k], dy[k], dz[k]),
                                     pdf[k], &parts);
        if (p.guide_learn) {
            P.guide_parts[slots[k]] = parts;
            P.shadow_key[slots[k]] = etk_guide_record_key(p.env, cell[k], make_float2(u[k], v[k]));
        }
    }
    etk_guide_store_batch(S, P, p, slots, cell, n, u, v, dx, dy, dz, pdf);
}

ETK_END

#endif
