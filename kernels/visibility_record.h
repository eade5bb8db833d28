// The visibility strategy's shadow-ray records, summed where they are made: in the shadow stage,
// on the device, into one buffer of sums the host reads (and zeroes) only when it rebuilds the
// tables (host/lib/render/visibility_cache.h says what the sums mean and how the tables come from
// them). No record crosses to the host between bounces, so a GPU keeps its learning passes on
// the device, and the native back end's threads add their own records as they trace.
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
//   counts  slots words: the records per cell
//   m2      slots pairs: per cell, the light sample's second moment
//   moments slots x ETK_PORTAL_CANDIDATES pairs: per cell and candidate portal share b, the
//           light sample's second moment had it been drawn with share b
//   portal  ETK_PORTAL_CELLS pairs: per cell of the scene's box, the unoccluded records' values
//   records 1 pair: the records with a cell
#ifndef ETK_VISIBILITY_RECORD_H
#define ETK_VISIBILITY_RECORD_H
#include "compat.h"
#include "params.h"
#include "portal_guide.h"
#include "visibility_guide.h"

// Fixed point: a value of the map's power counts 2^28; one record at most 2^12 of that (a single
// sample that large is a firefly, not information), so a cell holds 2^24 such records.
#define ETK_GUIDE_UNIT 268435456.0f // 2^28
#define ETK_GUIDE_MAX_RECORD 4096.0f

ETK_BEGIN

ETK_FN int etk_gsum_counts(int slots) {
    return 2 * slots * ETK_GUIDE_REGIONS;
}
ETK_FN int etk_gsum_m2(int slots) {
    return etk_gsum_counts(slots) + slots;
}
ETK_FN int etk_gsum_moments(int slots) {
    return etk_gsum_m2(slots) + 2 * slots;
}
ETK_FN int etk_gsum_portal(int slots) {
    return etk_gsum_moments(slots) + 2 * slots * ETK_PORTAL_CANDIDATES;
}
ETK_FN int etk_gsum_records(int slots) {
    return etk_gsum_portal(slots) + 2 * ETK_PORTAL_CELLS;
}
ETK_FN int etk_gsum_words(int slots) {
    return etk_gsum_records(slots) + 2;
}

// v >= 0 (relative to the map's power) in fixed point, capped.
ETK_FN ulong etk_guide_fixed(float v) {
    return (ulong)(fmin(v, ETK_GUIDE_MAX_RECORD) * ETK_GUIDE_UNIT + 0.5f);
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

// One shadow ray's record: its key (cell x regions + region of its direction; outside the table:
// no cell), its value (luminance(L) cos / pdf if nothing blocked it, else 0), the box cell it
// leaves by (-1: blocked) and the densities p_vis, p_portal of its direction. box: the portal
// table the ray was drawn with (its cells' shares).
ETK_FN void etk_guide_record_light(ETK_ATOMIC_PTR sums, EtkParams p, ETK_GLOBAL const float* box,
                                   int key, float value, int exit, float2 parts) {
    int slots = p.guide_slots;
    float v = (isfinite(value) ? fmax(value, 0.0f) : 0.0f) * p.guide_inv_power;
    ulong fv = etk_guide_fixed(v);
    if (exit >= 0 && exit < ETK_PORTAL_CELLS && fv != 0)
        etk_add_wide(sums + etk_gsum_portal(slots) + 2 * exit, fv);
    if (key < 0 || key >= slots * ETK_GUIDE_REGIONS)
        return;
    int s = key / ETK_GUIDE_REGIONS;
    etk_add_wide(sums + etk_gsum_records(slots), 1);
    etk_add_wide(sums + 2 * key, fv);
    ETK_ATOMIC_INC(sums + etk_gsum_counts(slots) + s);
    if (!(v > 0.0f) || !isfinite(parts.x) || !isfinite(parts.y))
        return;
    // A diffuse vertex's light sample estimates (albedo / pi) v: its second moment, in the unit
    // the light sample count shares with the continuation's (albedo^2 dropped).
    float e = v * (1.0f / ETK_PI);
    etk_add_wide(sums + etk_gsum_m2(slots) + 2 * s, etk_guide_fixed(e * e));
    // v = g / p_rec (g = luminance(L) cos, unoccluded); the second moment of the light sample
    // with share b is E_rec[g^2 / (p_rec p_b)] = E_rec[v^2 p_rec / p_b].
    float b0 = box[ETK_PORTAL_SHARES + s];
    float prec = (1.0f - b0) * parts.x + b0 * parts.y;
    ETK_ATOMIC_PTR m = sums + etk_gsum_moments(slots) + 2 * s * ETK_PORTAL_CANDIDATES;
    for (int j = 0; j < ETK_PORTAL_CANDIDATES; ++j) {
        float b = etk_portal_candidate(j);
        float pb = (1.0f - b) * parts.x + b * parts.y;
        etk_add_wide(m + 2 * j,
                     etk_guide_fixed(pb > 0.0f ? v * v * prec / pb : ETK_GUIDE_MAX_RECORD));
    }
}

ETK_END

#endif
