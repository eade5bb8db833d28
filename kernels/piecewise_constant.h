// Piecewise-constant 1D and 2D distributions sampled by binary search (paper, Figures 2 and 3).
//
// A 2D distribution of w columns (u) by h rows (v) lives in one flat float array:
//   [0, h)                      marginal density over rows, p(v)
//   [h, 2h+1)                   marginal CDF, h+1 entries, 0 ... 1
//   [2h+1, 2h+1+h*w)            conditional densities p(u|v), one row of w after another
//   [2h+1+h*w, 2h+1+h*(2w+1))   conditional CDFs, w+1 entries per row
// Densities are over the unit interval (they average to one over a row with any light), so the
// joint density on the unit square is p(u,v) = p(v) p(u|v). A function that sums to zero keeps a
// linear CDF and zero densities: it is never chosen and evaluates to zero, without a division by 0.
// Offsets are 32-bit ints, as on the device: they are exact while etk_dist2d_size(w, h) fits in an
// int and w, h <= 65536, which the host checks before it builds a table (check_distribution_size
// in host/lib/load/env_distribution.cpp, in 64-bit arithmetic).
#ifndef ETK_PIECEWISE_CONSTANT_H
#define ETK_PIECEWISE_CONSTANT_H
#include "compat.h"

ETK_BEGIN

ETK_FN int etk_dist2d_marginal_cdf(int h) {
    return h;
}
ETK_FN int etk_dist2d_conditional_pdf(int h) {
    return 2 * h + 1;
}
ETK_FN int etk_dist2d_conditional_cdf(int w, int h) {
    return 2 * h + 1 + h * w;
}
ETK_FN int etk_dist2d_size(int w, int h) {
    return 2 * h + 1 + h * (2 * w + 1);
}

// Largest i in [0, n-1] with cdf[i] <= u, for a CDF of n+1 entries. Cells of zero width are
// never returned for u in [0,1): the last of a run of equal entries is the one whose successor
// is larger.
ETK_FN int etk_find_interval(ETK_GLOBAL const float* cdf, int n, float u) {
    // Binary lifting with no branches and a number of steps that depends on n only: every
    // work-item runs the same instructions, so OpenCL compilers can vectorise across work-items.
    // Steps of n or more never move (mid >= n), so the search starts at the largest power of
    // two below n: log2(n) steps rather than 17 (issue 12), the same result.
    int first = 1;
    while (2 * first < n)
        first *= 2;
    int lo = 0; // invariant: cdf[lo] <= u
    for (int step = first; step > 0; step >>= 1) {
        int mid = lo + step;
        float c = cdf[min(mid, n - 1)];
        lo = (mid < n && c <= u) ? mid : lo;
    }
    return lo;
}

ETK_FN int etk_cell_of(float x, int n) {
    return clamp((int)(x * (float)n), 0, n - 1);
}

// Continuous coordinate in [i/n, (i+1)/n) for offset t in [0,1): rounding never leaves the cell,
// so the density evaluated at the result is the density of the chosen cell. The division can
// round across either edge (e.g. 53/100 rounds below 0.53): step back by one float at a time.
ETK_FN float etk_cell_coordinate(int i, float t, int n) {
    float x = ((float)i + t) / (float)n;
    float hi = (float)(i + 1) / (float)n;
    x = x < hi ? x : as_float(as_uint(hi) - 1u);
    // Rounding is off by at most a float step or two; fixed-count steps keep this branch-free.
    for (int k = 0; k < 2; ++k)
        x = etk_cell_of(x, n) < i ? as_float(as_uint(x) + 1u) : x;
    for (int k = 0; k < 2; ++k)
        x = etk_cell_of(x, n) > i ? as_float(as_uint(x) - 1u) : x;
    return x;
}

// Samples a 1D piecewise-constant density over [0,1]: returns x, its density and its cell.
ETK_FN float etk_sample_1d(ETK_GLOBAL const float* pdf, ETK_GLOBAL const float* cdf, int n, float u,
                           float* density, int* cell) {
    int i = etk_find_interval(cdf, n, u);
    float width = cdf[i + 1] - cdf[i];
    float t = width > 0.0f ? (u - cdf[i]) / width : 0.5f;
    // t > 0: x is never exactly 0, where the lat-long density has its zero at the pole.
    t = clamp(t, 5.9604645e-8f, ETK_ONE_MINUS_EPS);
    *density = pdf[i];
    *cell = i;
    return etk_cell_coordinate(i, t, n);
}

// Samples (u, v) on the unit square: row from the marginal, column from that row's conditional.
ETK_FN float2 etk_sample_2d(ETK_GLOBAL const float* dist, int w, int h, float2 xi, float* density,
                            int* row, int* col) {
    float pv, pu;
    float v = etk_sample_1d(dist, dist + etk_dist2d_marginal_cdf(h), h, xi.y, &pv, row);
    ETK_GLOBAL const float* cpdf = dist + etk_dist2d_conditional_pdf(h) + *row * w;
    ETK_GLOBAL const float* ccdf = dist + etk_dist2d_conditional_cdf(w, h) + *row * (w + 1);
    float u = etk_sample_1d(cpdf, ccdf, w, xi.x, &pu, col);
    *density = pv * pu;
    return make_float2(u, v);
}

ETK_FN float etk_pdf_2d(ETK_GLOBAL const float* dist, int w, int h, float2 uv) {
    int row = etk_cell_of(uv.y, h);
    int col = etk_cell_of(uv.x, w);
    return dist[row] * dist[etk_dist2d_conditional_pdf(h) + row * w + col];
}

ETK_END

#endif
