// Piecewise-constant 1D and 2D distributions sampled by binary search (paper, Figures 2 and 3).
//
// A 2D distribution of w columns (u) by h rows (v) lives in one flat float array:
//   [0, h)                      marginal density over rows, p(v)
//   [h, 2h+1)                   marginal CDF, h+1 entries, 0 ... 1
//   [2h+1, 2h+1+h*w)            conditional densities p(u|v), one row of w after another
//   [2h+1+h*w, 2h+1+h*(2w+1))   conditional CDFs, w+1 entries per row
//   then the guide tables (cutpoint method): Kh+1 entries for the marginal CDF, then
//   Kw+1 per conditional CDF, K = etk_guide_cells(n). Entry k is the interval
//   etk_find_interval returns for u = k/K (entry K: n-1), stored as a float holding an exact
//   integer (n <= 65536), so one flat float table still holds the whole distribution and a
//   guide can never be paired with another table's CDFs (plain and MIS-compensated twins).
// Densities are over the unit interval (they average to one over a row with any light), so the
// joint density on the unit square is p(u,v) = p(v) p(u|v). A function that sums to zero keeps a
// linear CDF and zero densities: a row without light has zero marginal width, so it is never
// chosen and evaluates to zero (a table without any light is gated by the map's has_light).
// Sampling and evaluation take densities from the CDFs' widths (etk_interval_density); the stored
// densities serve the host (the builder's workspace, the compensated twin's input).
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
// Guide cells of a CDF over n intervals: the largest power of two <= n/2 (at least 1), so u*K
// and k/K are exact in float and a cell holds about two intervals on average; the guides add about
// a quarter to the table (a 1024-wide row: 513 guide entries next to 2,049 density and CDF ones).
ETK_FN int etk_guide_cells(int n) {
    // 2^(floor(log2 n) - 1) from the leading zeros, not a loop: the table offsets below call it
    // several times per sample (as a loop it was half of a sample's instructions).
    int lg = 31 - (int)clz((uint)max(n, 2));
    return 1 << (lg - 1);
}
ETK_FN int etk_dist2d_marginal_guide(int w, int h) {
    return 2 * h + 1 + h * (2 * w + 1);
}
ETK_FN int etk_dist2d_conditional_guide(int w, int h) {
    return etk_dist2d_marginal_guide(w, h) + etk_guide_cells(h) + 1;
}
ETK_FN int etk_dist2d_size(int w, int h) {
    return etk_dist2d_conditional_guide(w, h) + h * (etk_guide_cells(w) + 1);
}

// One step of binary lifting over cdf[lo .. last]: lo + step where cdf[lo + step] <= u (and
// lo + step <= last), else lo; a select, not a branch. etk_find_interval and
// etk_find_interval_between step with it, and the batched searches that run a batch's samples
// step by step (visibility_guide.h): a step of last - lo + 1 or more never moves lo.
ETK_FN int etk_interval_step(ETK_GLOBAL const float* cdf, int lo, int step, int last, float u) {
    int mid = lo + step;
    float c = cdf[min(mid, last)];
    return lo + (step & -((int)(mid <= last) & (int)(c <= u)));
}
// The first step of etk_find_interval over n intervals: the largest power of two below n (1 for n
// <= 2).
ETK_FN int etk_interval_first_step(int n) {
    int first = 1;
    while (2 * first < n)
        first *= 2;
    return first;
}
// The first step of etk_find_interval_between over [lo, lo + span]: the largest power of two <=
// span (1 for span <= 1).
ETK_FN int etk_interval_first_step_between(int span) {
    int step = 1;
    while (2 * step <= span)
        step *= 2;
    return step;
}

// Largest i in [0, n-1] with cdf[i] <= u, for a CDF of n+1 entries. Cells of zero width are
// never returned for u in [0,1): the last of a run of equal entries is the one whose successor
// is larger.
ETK_FN int etk_find_interval(ETK_GLOBAL const float* cdf, int n, float u) {
    // Binary lifting with no branches and a number of steps that depends on n only: every
    // work-item runs the same instructions, so OpenCL compilers can vectorise across work-items.
    // Steps of n or more never move (mid >= n), so the search starts at the largest power of
    // two below n: log2(n) steps rather than 17, the same result.
    int lo = 0; // invariant: cdf[lo] <= u
    for (int step = etk_interval_first_step(n); step > 0; step >>= 1)
        lo = etk_interval_step(cdf, lo, step, n - 1, u);
    return lo;
}

// The largest i in [lo, hi] with cdf[i] <= u, given cdf[lo] <= u: binary lifting from the
// largest power of two <= hi - lo, with selects rather than branches (the comparisons are
// unpredictable; only the trip count varies, and it is 0 or 1 for most short ranges).
ETK_FN int etk_find_interval_between(ETK_GLOBAL const float* cdf, int lo, int hi, float u) {
    for (int step = etk_interval_first_step_between(hi - lo); step > 0; step >>= 1)
        lo = etk_interval_step(cdf, lo, step, hi, u);
    return lo;
}

// The two halves of etk_find_interval_guided (below): the range [*lo, *hi] the answer for u lies
// in, from the guide (one load; etk_env_sample_batch_uv issues a batch's before any CDF read)...
ETK_FN void etk_guide_range(ETK_GLOBAL const float* guide, int n, float u, int* lo, int* hi) {
    int K = etk_guide_cells(n);
    int k = clamp((int)(u * (float)K), 0, K - 1);
    *lo = (int)guide[k];
    *hi = (int)guide[k + 1];
}
// ...and the answer within it: first the three CDF entries after lo (one cache line, most often;
// etk_env_sample_batch_uv reads a batch's before it searches any)...
ETK_FN float etk_interval_head_entry(ETK_GLOBAL const float* cdf, int n, int lo, int j) {
    return cdf[min(lo + 1 + j, n)]; // lo + 1 <= n always: the first entry is cdf[lo + 1]
}
ETK_FN float3 etk_interval_head(ETK_GLOBAL const float* cdf, int n, int lo) {
    return make_float3(etk_interval_head_entry(cdf, n, lo, 0),
                       etk_interval_head_entry(cdf, n, lo, 1),
                       etk_interval_head_entry(cdf, n, lo, 2));
}
// ...then the answer from them. Most cells hold at most two interval ends: the three entries are
// counted, and the binary search runs only when the answer lies beyond them (at most ~5% of the
// samples on the shipped maps). A sample's cost is the latency of its chain of dependent loads: a
// search whose trip count varies with the data mispredicts a branch on most samples, and a scan
// one entry at a time chains the loads.
// (Its two halves: whether the answer lies beyond the three entries, and the answer when not.)
// (Scalar arguments: a loop over a batch with no vector-typed values is one LLVM can vectorise.)
ETK_FN int etk_interval_beyond_head(int lo, int hi, float head2, float u) {
    return (lo + 3 <= hi) & (head2 <= u);
}
ETK_FN int etk_interval_in_head(int lo, int hi, float head0, float head1, float u) {
    return lo + (int)((lo + 1 <= hi) & (head0 <= u)) + (int)((lo + 2 <= hi) & (head1 <= u));
}
ETK_FN int etk_find_interval_after(ETK_GLOBAL const float* cdf, int lo, int hi, float3 head,
                                   float u) {
    if (etk_interval_beyond_head(lo, hi, head.z, u))
        return etk_find_interval_between(cdf, lo + 3, hi, u);
    return etk_interval_in_head(lo, hi, head.x, head.y, u);
}
ETK_FN int etk_find_interval_in(ETK_GLOBAL const float* cdf, int n, int lo, int hi, float u) {
    return etk_find_interval_after(cdf, lo, hi, etk_interval_head(cdf, n, lo), u);
}
// etk_find_interval's result, from the CDF's guide table (guide[k] = etk_find_interval(cdf, n,
// k/K) for k < K, guide[K] = n-1), for u in [0, 1]. K is a power of two, so the cell k =
// floor(u K) is exact: k/K <= u < (k+1)/K, hence guide[k] <= answer <= guide[k+1] (the CDF is
// monotone), and a search over that short range (about two intervals) finishes it. The
// same index as the plain search, so the same sample (tests/kernels/cdf_guide_test.cpp); the
// win is memory traffic: one guide line and one CDF line rather than log2(n) scattered reads.
ETK_FN int etk_find_interval_guided(ETK_GLOBAL const float* cdf, int n,
                                    ETK_GLOBAL const float* guide, float u) {
    int lo, hi;
    etk_guide_range(guide, n, u, &lo, &hi);
    return etk_find_interval_in(cdf, n, lo, hi, u);
}

ETK_FN int etk_cell_of(float x, int n) {
    return clamp((int)(x * (float)n), 0, n - 1);
}

// Whether n (> 0) is a power of two: etk_cell_coordinate's exact path.
ETK_FN int etk_is_pow2(int n) {
    return (n & (n - 1)) == 0;
}
// etk_cell_coordinate for n a power of two, inv = 1 / n (etk_inv_pow2).
ETK_FN float etk_cell_coordinate_pow2(int i, float t, float inv) {
    float hi = (float)(i + 1) * inv;
    float x = ((float)i + t) * inv;
    return x < hi ? x : as_float(as_uint(hi) - 1u);
}
// Continuous coordinate in [i/n, (i+1)/n) for offset t in [0,1): rounding never leaves the cell,
// so the density evaluated at the result is the density of the chosen cell. The division can
// round across either edge (e.g. 53/100 rounds below 0.53): step back by one float at a time.
ETK_FN float etk_cell_coordinate(int i, float t, int n) {
    // For n a power of two (most maps) dividing by n is exact scaling, a product by 1/n (no
    // division on the sample's critical path), and x n = fl(i + t) is >= i and, after the clamp,
    // below i + 1: x is in cell i already (1/n exact: etk_inv_pow2). Otherwise rounding can be off
    // by a float step or two, which fixed-count steps mend without branches. n is the same for
    // every sample of a table, so the branch between the two is predicted.
    if (etk_is_pow2(n))
        return etk_cell_coordinate_pow2(i, t, etk_inv_pow2((uint)n));
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

// Density of interval i of a CDF over n intervals on [0,1]: its width times n. It is the density
// inversion of this float CDF really samples with (the stored densities f n / sum differ from it
// by the CDF's rounding), so a sample's density and the density evaluated at its point are one
// number from the two CDF entries the sample has just read: sampling touches no density table
// (one cache line fewer per sample).
ETK_FN float etk_interval_density_between(float lo, float hi, int n) {
    return (hi - lo) * (float)n;
}
ETK_FN float etk_interval_density(ETK_GLOBAL const float* cdf, int n, int i) {
    return etk_interval_density_between(cdf[i], cdf[i + 1], n);
}

// Where u lies between the cell's CDF entries lo and hi, in (0, 1) (the middle for no width).
ETK_FN float etk_interval_t(float lo, float hi, float u) {
    float width = hi - lo;
    float t = width > 0.0f ? (u - lo) / width : 0.5f;
    // t > 0: x is never exactly 0, where the lat-long density has its zero at the pole.
    return clamp(t, 5.9604645e-8f, ETK_ONE_MINUS_EPS);
}
// The point in cell i of n on [0,1] for u between the cell's CDF entries lo and hi: inversion
// within the cell (its middle when it has no width).
ETK_FN float etk_interval_point(float lo, float hi, float u, int i, int n) {
    return etk_cell_coordinate(i, etk_interval_t(lo, hi, u), n);
}

// The point of interval i (found for u) of a 1D piecewise-constant density over [0,1]: returns
// x, its density and its cell.
ETK_FN float etk_sample_1d_in(ETK_GLOBAL const float* cdf, int n, int i, float u, float* density,
                              int* cell) {
    *density = etk_interval_density(cdf, n, i); // the entries the point is made from
    *cell = i;
    return etk_interval_point(cdf[i], cdf[i + 1], u, i, n);
}

// Samples a 1D piecewise-constant density over [0,1]: returns x, its density and its cell.
ETK_FN float etk_sample_1d(ETK_GLOBAL const float* cdf, int n, float u, float* density, int* cell) {
    return etk_sample_1d_in(cdf, n, etk_find_interval(cdf, n, u), u, density, cell);
}

// Row r's conditional CDF and its guide table.
ETK_FN ETK_GLOBAL const float* etk_dist2d_row_cdf(ETK_GLOBAL const float* dist, int w, int h,
                                                  int r) {
    return dist + etk_dist2d_conditional_cdf(w, h) + r * (w + 1);
}
ETK_FN ETK_GLOBAL const float* etk_dist2d_row_guide(ETK_GLOBAL const float* dist, int w, int h,
                                                    int r) {
    return dist + etk_dist2d_conditional_guide(w, h) + r * (etk_guide_cells(w) + 1);
}

// Samples (u, v) on the unit square: row from the marginal, column from that row's conditional,
// both by inversion of the CDF (the guide tables only find the interval faster).
// etk_env_sample_batch_uv (envmap.h) runs the same steps across a batch of samples.
ETK_FN float2 etk_sample_2d(ETK_GLOBAL const float* dist, int w, int h, float2 xi, float* density,
                            int* row, int* col) {
    ETK_GLOBAL const float* mcdf = dist + etk_dist2d_marginal_cdf(h);
    *row = etk_find_interval_guided(mcdf, h, dist + etk_dist2d_marginal_guide(w, h), xi.y);
    ETK_GLOBAL const float* ccdf = etk_dist2d_row_cdf(dist, w, h, *row);
    *col = etk_find_interval_guided(ccdf, w, etk_dist2d_row_guide(dist, w, h, *row), xi.x);
    float pu, pv;
    int cell;
    float v = etk_sample_1d_in(mcdf, h, *row, xi.y, &pv, &cell);
    float u = etk_sample_1d_in(ccdf, w, *col, xi.x, &pu, &cell);
    *density = pv * pu;
    return make_float2(u, v);
}

// The joint density etk_sample_2d samples with, at (u, v).
ETK_FN float etk_pdf_2d(ETK_GLOBAL const float* dist, int w, int h, float2 uv) {
    int row = etk_cell_of(uv.y, h);
    int col = etk_cell_of(uv.x, w);
    return etk_interval_density(dist + etk_dist2d_marginal_cdf(h), h, row) *
           etk_interval_density(etk_dist2d_row_cdf(dist, w, h, row), w, col);
}

ETK_END

#endif
