// The visibility strategy's records, summed where they are made, on the device, into one buffer
// of sums the host reads (and zeroes) only when it rebuilds the tables
// (host/lib/render/visibility_cache.h says what the sums mean and how the tables come from them):
// each shadow ray's in the shadow stage; each guided vertex's continuation at the end of its
// path (etk_guide_note_vertex keeps what the record needs until the path's radiance is known).
// No record crosses to the host between bounces, so a GPU keeps its learning passes on the
// device, and the native back end's threads add their own records as they trace.
//
// The sums are 64-bit fixed point, added as two 32-bit words with a carry (etk_add_wide): integer
// additions commute, so the sums -- and the tables -- do not depend on the order the records
// arrive in (threads, work-groups, lanes, back ends), and OpenCL 1.2's 32-bit atomics suffice on
// every device (no cl_khr_int64_base_atomics). Each record's own arithmetic is float, the same
// operations on both back ends.
//
// Layout, in 32-bit words for `slots` hash-grid cells (the host reads a word pair as one
// little-endian uint64, as every OpenCL device and the native host store it):
//   light   slots x ETK_GUIDE_REGIONS pairs: per cell and region, the records' values
//   cells   slots blocks of etk_gsum_cell_words words: per cell its statistics, side by side so
//           that a record adds to one or two cache lines of them (seven arrays of them took a line
//           each): ETK_GSUM_* below
//   portal  ETK_PORTAL_CELLS pairs: per cell of the scene's box, the unoccluded records' values
// and, with the continuation guide (p.guide_continuation), after them:
//   dir     slots x ETK_GUIDE_REGIONS pairs: per cell and region, the continuations' values
//   spot    ETK_PORTAL_CELLS pairs: per cell of the scene's box, the continuations' values
// A cell's block: the light records' part, then (with the continuation guide) the continuations'.
//   COUNT    the light records
//   M2       a pair: the light sample's second moment
//   MOMENTS  ETK_PORTAL_CANDIDATES pairs: the light sample's second moment had it been drawn with
//            candidate portal share b
//   REACH    a pair: the records' values had nothing blocked their rays (the regions' sums hold
//            those of the rays nothing blocked): the share of the light the scene lets through
//   DCOUNT   the continuation records
//   GCOUNT   the records in GUIDEDM
//   CM2      a pair: the continuation's second moment
//   SPOTM    ETK_PORTAL_CANDIDATES pairs: the guided continuation's second moment had it been
//            drawn with secondary-source share q
//   GUIDEDM  ETK_GUIDED_CANDIDATES pairs: the same per guided share c
// (No total of the records: the per-cell counts hold it, without one word every thread adds to.)
#ifndef ETK_VISIBILITY_RECORD_H
#define ETK_VISIBILITY_RECORD_H
#include "compat.h"
#include "continuation_guide.h"
#include "params.h"
#include "portal_guide.h"
#include "visibility_guide.h"

// Fixed point: a value of the map's power counts 2^28; one record at most 2^12 of that (a single
// sample that large is a firefly, not information), so a cell holds 2^24 such records.
#define ETK_GUIDE_UNIT 268435456.0f // 2^28
#define ETK_GUIDE_MAX_RECORD 4096.0f

ETK_BEGIN

#define ETK_GSUM_COUNT 0
#define ETK_GSUM_M2 1
#define ETK_GSUM_MOMENTS 3
#define ETK_GSUM_REACH (ETK_GSUM_MOMENTS + 2 * ETK_PORTAL_CANDIDATES)
#define ETK_GSUM_LIGHT_WORDS (ETK_GSUM_REACH + 2)
#define ETK_GSUM_DCOUNT ETK_GSUM_LIGHT_WORDS
#define ETK_GSUM_GCOUNT (ETK_GSUM_DCOUNT + 1)
#define ETK_GSUM_CM2 (ETK_GSUM_GCOUNT + 1)
#define ETK_GSUM_SPOTM (ETK_GSUM_CM2 + 2)
#define ETK_GSUM_GUIDEDM (ETK_GSUM_SPOTM + 2 * ETK_PORTAL_CANDIDATES)
#define ETK_GSUM_CELL_WORDS (ETK_GSUM_GUIDEDM + 2 * ETK_GUIDED_CANDIDATES)
#if ETK_GSUM_LIGHT_WORDS > 16 || ETK_GSUM_CELL_WORDS > 32
#error "a cell's statistics outgrow its block (etk_gsum_cell_words)"
#endif

// A cell's block: 16 or 32 words (one or two cache lines), with or without the continuations.
ETK_FN int etk_gsum_cell_words(int continuation) {
    return continuation ? 32 : 16;
}
ETK_FN int etk_gsum_cells(int slots) {
    return 2 * slots * ETK_GUIDE_REGIONS;
}
// The block of cell s.
ETK_FN int etk_gsum_cell(int slots, int continuation, int s) {
    return etk_gsum_cells(slots) + s * etk_gsum_cell_words(continuation);
}
ETK_FN int etk_gsum_portal(int slots, int continuation) {
    return etk_gsum_cell(slots, continuation, slots);
}
ETK_FN int etk_gsum_dir(int slots, int continuation) {
    return etk_gsum_portal(slots, continuation) + 2 * ETK_PORTAL_CELLS;
}
ETK_FN int etk_gsum_spot(int slots) {
    return etk_gsum_dir(slots, 1) + 2 * slots * ETK_GUIDE_REGIONS;
}
ETK_FN int etk_gsum_words(int slots, int continuation) {
    return continuation ? etk_gsum_spot(slots) + 2 * ETK_PORTAL_CELLS
                        : etk_gsum_dir(slots, continuation);
}

// A hint to load the line of the sums at w (the sums are volatile for the atomics; a prefetch
// takes a plain pointer).
#define etk_prefetch_sum(w) ETK_PREFETCH((ETK_GLOBAL const uint*)(w))

// v >= 0 (relative to the map's power) in fixed point, capped.
ETK_FN ulong etk_guide_fixed(float v) {
    return (ulong)(fmin(v, ETK_GUIDE_MAX_RECORD) * ETK_GUIDE_UNIT + 0.5f);
}

// A record's value relative to the map's power: negative and non-finite values count as 0.
ETK_FN float etk_guide_record_value(EtkParams p, float value) {
    return (isfinite(value) ? fmax(value, 0.0f) : 0.0f) * p.guide_inv_power;
}

// Adds v to the 64-bit sum in words w[0] (low) and w[1] (high): the low word's carry goes to the
// high word with it. Concurrent adds each carry their own, so the pair is exact once all are done
// (the host reads it only then).
ETK_FN void etk_add_wide(ETK_ATOMIC_PTR w, ulong v) {
    uint lo = (uint)v, hi = (uint)(v >> 32);
    if (lo != 0u) {
        uint old = ETK_ATOMIC_ADD(w, lo);
        hi += old + lo < old ? 1u : 0u;
    }
    if (hi != 0u)
        ETK_ATOMIC_ADD(w + 1, hi);
}

// The lines a shadow ray's record with `key` will add to, requested before the ray is traced: the
// traversal hides their latency (an atomic add waits for its line with nothing after it started).
ETK_FN void etk_guide_prefetch_light(ETK_ATOMIC_PTR sums, EtkParams p, int key) {
    int slots = p.guide_slots;
    if (key < 0 || key >= slots * ETK_GUIDE_REGIONS)
        return;
    ETK_ATOMIC_PTR cell =
        sums + etk_gsum_cell(slots, p.guide_continuation, key / ETK_GUIDE_REGIONS);
    etk_prefetch_sum(sums + 2 * key);
    etk_prefetch_sum(cell);
    etk_prefetch_sum(cell + ETK_GSUM_LIGHT_WORDS - 1);
}

// One shadow ray's record: its key (cell x regions + region of its direction; outside the table:
// no cell), its value (luminance(L) cos / pdf if nothing blocked it, else 0), the value it would
// have had unblocked (reach), the box cell it leaves by (-1: blocked) and the densities p_vis,
// p_portal of its direction. box: the portal table the ray was drawn with (its cells' shares).
ETK_FN void etk_guide_record_light(ETK_ATOMIC_PTR sums, EtkParams p, ETK_GLOBAL const float* box,
                                   int key, float value, float reach, int exit, float2 parts) {
    int slots = p.guide_slots;
    float v = etk_guide_record_value(p, value);
    ulong fv = etk_guide_fixed(v);
    if (exit >= 0 && exit < ETK_PORTAL_CELLS && fv != 0)
        etk_add_wide(sums + etk_gsum_portal(slots, p.guide_continuation) + 2 * exit, fv);
    if (key < 0 || key >= slots * ETK_GUIDE_REGIONS)
        return;
    int s = key / ETK_GUIDE_REGIONS;
    ETK_ATOMIC_PTR cell = sums + etk_gsum_cell(slots, p.guide_continuation, s);
    etk_add_wide(sums + 2 * key, fv);
    ETK_ATOMIC_INC(cell + ETK_GSUM_COUNT);
    ulong fr = etk_guide_fixed(etk_guide_record_value(p, reach));
    if (fr != 0)
        etk_add_wide(cell + ETK_GSUM_REACH, fr);
    if (!(v > 0.0f) || !isfinite(parts.x) || !isfinite(parts.y))
        return;
    // A diffuse vertex's light sample estimates (albedo / pi) v: its second moment, in the unit
    // the light sample count shares with the continuation's (albedo^2 dropped).
    float e = v * (1.0f / ETK_PI);
    etk_add_wide(cell + ETK_GSUM_M2, etk_guide_fixed(e * e));
    // v = g / p_rec (g = luminance(L) cos, unoccluded); the second moment of the light sample
    // with share b is E_rec[g^2 / (p_rec p_b)] = E_rec[v^2 p_rec / p_b].
    float b0 = box[ETK_PORTAL_SHARES + s];
    float prec = (1.0f - b0) * parts.x + b0 * parts.y;
    ETK_ATOMIC_PTR m = cell + ETK_GSUM_MOMENTS;
    for (int j = 0; j < ETK_PORTAL_CANDIDATES; ++j) {
        float b = etk_portal_candidate(j);
        float pb = (1.0f - b) * parts.x + b * parts.y;
        etk_add_wide(m + 2 * j,
                     etk_guide_fixed(pb > 0.0f ? v * v * prec / pb : ETK_GUIDE_MAX_RECORD));
    }
}

// One guided vertex's continuation record: key (cell x regions + the equal-area region of the
// direction), value luminance(L_in) / p (L_in the radiance the rest of the path brought back
// along it), the ray's origin o, direction d and density p. cells: the tables the continuation
// was drawn with (guide_cells). What the sums take, and why: visibility_cache.h.
ETK_FN void etk_guide_record_continuation(ETK_ATOMIC_PTR sums, EtkParams p,
                                          ETK_GLOBAL const float* cells, int key, float value,
                                          float3 o, float3 d, float prec) {
    int slots = p.guide_slots;
    if (key < 0 || key >= slots * ETK_GUIDE_REGIONS)
        return;
    float v = etk_guide_record_value(p, value);
    int s = key / ETK_GUIDE_REGIONS;
    ETK_GLOBAL const float* spot = cells + etk_portal_offset(slots, 1) + etk_portal_size(slots);
    float t;
    int exit = etk_portal_exit(spot, o, d, &t);
    // The densities the record was drawn with: the cell's guide, the spot table, the BSDF's.
    ETK_GLOBAL const float* dir = cells + etk_guide_dir_offset(slots, s);
    float c = dir[ETK_GUIDE_DIR_SHARE];
    float q = spot[ETK_PORTAL_ON] > 0.0f ? spot[ETK_PORTAL_SHARES + s] : 0.0f;
    float pg = etk_cguide_pdf_of_region(dir, key % ETK_GUIDE_REGIONS); // key: d's region
    float ps = etk_portal_pdf_exit(spot, d, exit, t);
    // p_b from the mixture the record was drawn with (its BSDF part taken out).
    float pb =
        c < 1.0f ? fmax(0.0f, (prec - etk_cguide_mix(c, q, pg, ps, 0.0f)) / (1.0f - c)) : 0.0f;
    // The tables learn luminance(L_in) cos / p = pi p_b v (p_b = cos / pi at a diffuse vertex,
    // the only kind that is guided): both follow the integrand's incident radiance x cosine. A
    // glossy vertex's record, drawn from its lobe alone (p_rec = its p_b, recovered here with the
    // cell's share c), weighs at most pi luminance(L_in) / (1 - c).
    ulong g = etk_guide_fixed(isfinite(pb) ? ETK_PI * pb * v : 0.0f);
    ETK_ATOMIC_PTR cell = sums + etk_gsum_cell(slots, 1, s);
    etk_add_wide(sums + etk_gsum_dir(slots, 1) + 2 * key, g);
    ETK_ATOMIC_INC(cell + ETK_GSUM_DCOUNT);
    if (exit >= 0 && exit < ETK_PORTAL_CELLS && g != 0)
        etk_add_wide(sums + etk_gsum_spot(slots) + 2 * exit, g);
    if (!(v > 0.0f) || !(pb > 0.0f) || !isfinite(prec * ps * pg))
        return;
    // The continuation's estimate at a diffuse vertex, f cos L / p = albedo p_bsdf v: its second
    // moment in the light sample count's unit.
    etk_add_wide(cell + ETK_GSUM_CM2, etk_guide_fixed(pb * v * pb * v));
    float m2 = v * v * prec * pb * pb;
    ETK_ATOMIC_PTR sm = cell + ETK_GSUM_SPOTM;
    for (int j = 0; j < ETK_PORTAL_CANDIDATES; ++j) {
        float pq = etk_cguide_mix(p.guide_continuation_share, etk_portal_candidate(j), pg, ps, pb);
        etk_add_wide(sm + 2 * j, etk_guide_fixed(pq > 0.0f ? m2 / pq : ETK_GUIDE_MAX_RECORD));
    }
    // The guided share's moments, with the cell's spot share; from the first update on (the
    // prior guide is uniform: its records would only tell that it is worse than the BSDF).
    if (!p.guide_ready)
        return;
    ETK_ATOMIC_INC(cell + ETK_GSUM_GCOUNT);
    ETK_ATOMIC_PTR gm = cell + ETK_GSUM_GUIDEDM;
    for (int j = 0; j < ETK_GUIDED_CANDIDATES; ++j) {
        float pc = etk_cguide_mix(etk_guided_candidate(j), q, pg, ps, pb);
        etk_add_wide(gm + 2 * j, etk_guide_fixed(pc > 0.0f ? m2 / pc : ETK_GUIDE_MAX_RECORD));
    }
}

// What a continuation record needs of guided vertex k (its depth) of the path in `slot` until
// the path ends: the continuation ray (origin, density; direction, key), the throughput after the
// vertex and the radiance so far, in ETK_GUIDE_VERTEX_FLOAT4S float4s. Called where the ray is
// traced (the next bounce's intersect stage), after the vertex's shadow ray added its light.
// The key is stored as a float's value, not its bits: a small integer's bits are a denormal, and
// clang (PoCL) computes with a float3's fourth lane, which holds the float4's w: the record's
// box exit, o + d t, took a microcode assist per record (a fifth of PoCL's accumulate stage).
ETK_FN void etk_guide_note_vertex(EtkPaths P, int slot, int k) {
    if (k >= ETK_GUIDE_VERTICES)
        return; // deeper vertices teach the guide nothing (their records are not kept)
    float4 d = P.ray_d[slot];
    int key = P.ray_cell[slot] * ETK_GUIDE_REGIONS + etk_cguide_region(etk_xyz(d));
    ETK_GLOBAL float4* r = P.guide_vertices[slot].v + ETK_GUIDE_VERTEX_FLOAT4S * k;
    r[0] = etk_f4(etk_xyz(P.ray_o[slot]), P.ray_pdf[slot]);
    r[1] = etk_f4(etk_xyz(d), (float)key); // exact (ETK_GUIDE_MAX_SLOTS)
    r[2] = P.beta[slot];
    r[3] = P.radiance[slot];
    P.guide_noted[slot] |= 1 << k;
}

// At the path's end: the continuation records of its noted vertices, the radiance each brought
// back being the path's final radiance less the radiance at the vertex, over its throughput.
ETK_FN void etk_guide_record_path(EtkScene S, EtkPaths P, ETK_ATOMIC_PTR sums, EtkParams p,
                                  int slot) {
    float3 end = etk_xyz(P.radiance[slot]);
    int noted = P.guide_noted[slot], slots = p.guide_slots;
    // The records' keys scatter over tens of megabytes of sums and tables, and an atomic add
    // waits for its line with nothing after it started (x86): every line the records will touch
    // is requested first (natively, room000_d5: the records took 1.3x the time without).
    for (int k = 0; k < ETK_GUIDE_VERTICES; ++k) {
        if (!(noted & (1 << k)))
            continue;
        int key = (int)P.guide_vertices[slot].v[ETK_GUIDE_VERTEX_FLOAT4S * k + 1].w;
        if (key < 0 || key >= slots * ETK_GUIDE_REGIONS)
            continue;
        int c = key / ETK_GUIDE_REGIONS;
        etk_prefetch_sum(sums + etk_gsum_dir(slots, 1) + 2 * key);
        ETK_PREFETCH(S.guide_cells + etk_guide_dir_offset(slots, c) + key % ETK_GUIDE_REGIONS);
        ETK_PREFETCH(S.guide_cells + etk_guide_dir_offset(slots, c) + ETK_GUIDE_DIR_SHARE);
        etk_prefetch_sum(sums + etk_gsum_cell(slots, 1, c) + ETK_GSUM_DCOUNT);
        etk_prefetch_sum(sums + etk_gsum_cell(slots, 1, c) + ETK_GSUM_CELL_WORDS - 1);
    }
    for (int k = 0; k < ETK_GUIDE_VERTICES; ++k) {
        if (!(noted & (1 << k)))
            continue;
        ETK_GLOBAL const float4* r = P.guide_vertices[slot].v + ETK_GUIDE_VERTEX_FLOAT4S * k;
        float3 beta = etk_xyz(r[2]), before = etk_xyz(r[3]);
        float3 L = make_float3(beta.x > 0.0f ? (end.x - before.x) / beta.x : 0.0f,
                               beta.y > 0.0f ? (end.y - before.y) / beta.y : 0.0f,
                               beta.z > 0.0f ? (end.z - before.z) / beta.z : 0.0f);
        float4 o = r[0], d = r[1];
        etk_guide_record_continuation(sums, p, S.guide_cells, (int)d.w, etk_luma(L) * (1.0f / o.w),
                                      etk_xyz(o), etk_xyz(d), o.w);
    }
}

ETK_END

#endif
