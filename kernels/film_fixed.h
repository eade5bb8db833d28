// The film's exact sums (host/lib/render/film_sums.h) as the device keeps them: a float sample
// becomes a 128-bit fixed-point number of units of 2^-70, held as two 64-bit words (low first:
// the host's int128 on a little-endian machine), and sums of them are integer additions, so the
// device's sums of a render's passes equal the host's bit for bit, in any order. The host folds
// its passes with these same conversions; a GPU folds each pass where it was rendered instead of
// sending the film across the bus (ClDevice::fold_film).
#ifndef ETK_FILM_FIXED_H
#define ETK_FILM_FIXED_H
#include "compat.h"

ETK_BEGIN

#define ETK_FILM_FRACTION_BITS 70
// Samples of this magnitude (2^56) or more are flagged, never added (what a sum holds:
// host/lib/render/film_sums.h).
#define ETK_FILM_FIXED_LIMIT 72057594037927936.0f
// Flags of a channel that met a sample it cannot add (FilmSums::kPositiveOverflow ...).
#define ETK_FILM_POSITIVE_OVERFLOW 1u
#define ETK_FILM_NEGATIVE_OVERFLOW 2u
#define ETK_FILM_NAN 4u

typedef struct {
    ulong lo, hi;
} EtkFixed128;

// One pixel's sums, byte for byte FilmSums::Pixel: RGB sums and sums of squares as (lo, hi)
// pairs, the number of samples, a flag byte per channel.
typedef struct {
    ulong sum[6];
    ulong sq[6];
    uint count;
    uchar special[6];
    uchar pad[6];
} EtkFixedPixel;

// The flag a sample raises instead of being added (0: it is added).
ETK_FN uint etk_fixed_special(float v) {
    if (v != v)
        return ETK_FILM_NAN;
    if (!(fabs(v) < ETK_FILM_FIXED_LIMIT))
        return v > 0.0f ? ETK_FILM_POSITIVE_OVERFLOW : ETK_FILM_NEGATIVE_OVERFLOW;
    return 0u;
}

// A finite sample with |v| < 2^56 in units of 2^-70, rounded to nearest (ties away from zero),
// two's complement.
ETK_FN EtkFixed128 etk_fixed_from_float(float v) {
    const uint bits = as_uint(v);
    const uint exponent = (bits >> 23) & 0xffu;
    ulong mantissa = (ulong)(bits & 0x7fffffu);
    int e; // v = mantissa * 2^e
    if (exponent == 0u) {
        e = -149; // subnormal
    } else {
        mantissa |= (ulong)0x800000u;
        e = (int)exponent - 150;
    }
    const int shift = e + ETK_FILM_FRACTION_BITS; // at most 102 below the limit
    EtkFixed128 x;
    x.lo = 0;
    x.hi = 0;
    if (shift >= 64) {
        x.hi = mantissa << (shift - 64);
    } else if (shift > 0) {
        x.lo = mantissa << shift;
        x.hi = mantissa >> (64 - shift); // the bits shifted out of the low word
    } else if (shift == 0) {
        x.lo = mantissa;
    } else if (shift > -25) {
        x.lo = (mantissa + ((ulong)1 << (-shift - 1))) >> -shift;
    }                 // else below half a unit: 0
    if (bits >> 31) { // -x = ~x + 1, the carry into the high word where the low one wraps to 0
        x.lo = ~x.lo + 1;
        x.hi = ~x.hi + (x.lo == 0 ? 1 : 0);
    }
    return x;
}

// Adds a sample to a channel's sum (acc[0] low word, acc[1] high) or raises its flag.
ETK_FN void etk_fixed_add(ETK_GLOBAL ulong* acc, ETK_GLOBAL uchar* special, float v) {
    const uint flag = etk_fixed_special(v);
    if (flag != 0u) {
        *special = (uchar)(*special | flag);
        return;
    }
    const EtkFixed128 x = etk_fixed_from_float(v);
    const ulong lo = acc[0] + x.lo;
    acc[1] = acc[1] + x.hi + (lo < x.lo ? 1 : 0);
    acc[0] = lo;
}

// Adds one pass's pixel: its sample's RGB (w: 1 if the pass has a sample here, else 0) and the
// RGB of its square.
ETK_FN void etk_fixed_add_pixel(ETK_GLOBAL EtkFixedPixel* p, float4 sum, float4 sq) {
    etk_fixed_add(p->sum + 0, p->special + 0, sum.x);
    etk_fixed_add(p->sum + 2, p->special + 1, sum.y);
    etk_fixed_add(p->sum + 4, p->special + 2, sum.z);
    etk_fixed_add(p->sq + 0, p->special + 3, sq.x);
    etk_fixed_add(p->sq + 2, p->special + 4, sq.y);
    etk_fixed_add(p->sq + 4, p->special + 5, sq.z);
    p->count += (uint)sum.w;
}

ETK_END

#endif
