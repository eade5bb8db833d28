// sin/cos of pi x and atan2 as plain polynomials, used by every shared formula instead of the
// math library: host and device then evaluate the very same operations (no libm vs OpenCL
// built-in differences between the back ends), and the code has no calls or data-dependent
// loops, so OpenCL compilers can vectorise it across work-items. Accuracy: a few float ulps.
#ifndef ETK_TRIG_H
#define ETK_TRIG_H
#include "compat.h"

ETK_BEGIN

// sin(pi x) and cos(pi x): x = q/2 + r with |r| <= 1/4, Taylor series of degree 9 and 10 in
// t = pi r (truncation below 2e-9).
ETK_FN float2 etk_sincospi(float x) {
    float q = floor(2.0f * x + 0.5f);
    float r = x - 0.5f * q;
    int qi = ((int)q) & 3;
    float t = ETK_PI * r, t2 = t * t;
    float sp =
        t * (1.0f + t2 * (-1.6666667e-1f +
                          t2 * (8.3333333e-3f + t2 * (-1.9841270e-4f + t2 * 2.7557319e-6f))));
    float cp =
        1.0f +
        t2 * (-0.5f + t2 * (4.1666667e-2f +
                            t2 * (-1.3888889e-3f + t2 * (2.4801587e-5f - t2 * 2.7557319e-7f))));
    // The quadrant by bit operations (swap, then sign bits): compilers turn the selects into
    // branches, and the quadrant of a sampled direction is random (a misprediction per call).
    uint swap = 0u - (uint)(qi & 1);
    uint sb = as_uint(sp), cb = as_uint(cp);
    float s = as_float(((cb & swap) | (sb & ~swap)) ^ ((uint)(qi & 2) << 30));
    float c = as_float(((sb & swap) | (cb & ~swap)) ^ ((uint)((qi + 1) & 2) << 30));
    return make_float2(s, c);
}
ETK_FN float etk_sinpi(float x) {
    return etk_sincospi(x).x;
}
ETK_FN float etk_cospi(float x) {
    return etk_sincospi(x).y;
}

// atan2(y, x) in [-pi, pi]: atan on [0, 1] reduced to |z| <= tan(pi/8) by
// atan(a) = pi/4 + atan((a - 1) / (a + 1)), then its Taylor series to z^17 (truncation 3e-9).
ETK_FN float etk_atan2(float y, float x) {
    float ax = fabs(x), ay = fabs(y);
    float mx = fmax(ax, ay), mn = fmin(ax, ay);
    float a = mx > 0.0f ? mn / mx : 0.0f;
    int big = a > 0.41421356f;
    float z = big ? (a - 1.0f) / (a + 1.0f) : a;
    float z2 = z * z;
    float p = -1.0f / 15.0f + z2 * (1.0f / 17.0f);
    p = 1.0f / 13.0f + z2 * p;
    p = -1.0f / 11.0f + z2 * p;
    p = 1.0f / 9.0f + z2 * p;
    p = -1.0f / 7.0f + z2 * p;
    p = 1.0f / 5.0f + z2 * p;
    p = -1.0f / 3.0f + z2 * p;
    float r = z + z * z2 * p;
    r = big ? r + 0.25f * ETK_PI : r;
    r = ay > ax ? 0.5f * ETK_PI - r : r;
    r = x < 0.0f ? ETK_PI - r : r;
    return y < 0.0f ? -r : r;
}

ETK_END

#endif
