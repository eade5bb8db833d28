// Environment sampling that learns visibility (the visibility strategy). In a room lit
// through windows most directions the map's distribution picks hit a wall: the map knows the
// light, not what blocks it. A hash grid over surface positions (with the dominant axis and sign
// of the geometric normal) holds per cell a distribution over ETK_GUIDE_REGIONS coarse lat-long
// regions of the map, learned from the outcomes of earlier shadow rays
// (host/lib/render/visibility_cache.h). The light sample's density is the mixture
//   alpha x the map's distribution  +  (1 - alpha) x (region R from the cell's learned table P,
//                                                     then a direction inside R in proportion
//                                                     to the map),
// p(w) = p_map(w) (alpha + (1 - alpha) P(R(w)) / M_R(w)), M_R the map's mass in R: positive
// wherever the map is (unbiased), and evaluated the same way for MIS by etk_escaped. Both
// parts are proportional to the map inside every region, so the mixture is one hierarchical
// distribution: a region with probability Q(R) = alpha M_R + (1 - alpha) P(R) (the table a cell
// holds), then the map inside it. It is sampled by inverting it -- the region's row band and
// column from the two coordinates of the sample point, each rescaled to [0, 1) for the next
// level, then the map's own CDFs restricted to the region -- so, like the paper's warp, it
// keeps the stratification of the Sobol' points (a separate technique or region choice would
// thin them at random; measured on window_room, that was not where the strategy loses to the
// Sobol' points: docs/history/results-journal.md). Collisions of the hash merge two cells' tables:
// the density stays the one sampled, only less well fitted.
//
// guide_regions: [0, K) the map's mass per region, M_R (sum 1); then, per region column C and
// row R, the CDF over the region's distribution rows of p(v_r) x the row's mass in C's columns:
// rows(R) + 1 entries at K + C (h + ETK_GUIDE_ROWS) + row_start(R) + R; then, per distribution
// row r, its conditional CDF at the starts of ETK_GUIDE_SPLITS sub-bands of every column band
// (ETK_GUIDE_COLS x ETK_GUIDE_SPLITS + 1 entries, copies of the map's CDF entries: 260 bytes a
// row, 130 KB for a 512-row map, small enough to stay in cache). A guided sample reads the ends
// of its region's columns and finds its sub-band there, then searches only the sub-band's
// entries of the map's row (17 of them for a 1024-wide map: one line, sometimes two): one
// cache miss where the band's two ends in the map's row, the row's guide entry and the search
// took three or four, for the same column (etk_guide_column).
// guide_cells: per slot, ETK_GUIDE_CELL_FLOATS = K + 1 CDF entries of Q over the regions (0 ...
// 1), row-major (R = row band x ETK_GUIDE_COLS + column), so entry ETK_GUIDE_COLS x b is the CDF
// of the row bands, and the cell's light-sample count (etk_guide_light_count); then, when the
// continuation is guided (continuation_guide.h), per slot ETK_GUIDE_DIR_FLOATS: K + 1 CDF entries
// over the sphere's equal-area regions, same layout, and the share of continuations drawn from it.
// Two halves rather than one record per slot, so that the light sample's tables stay as compact as
// they were.
#ifndef ETK_VISIBILITY_GUIDE_H
#define ETK_VISIBILITY_GUIDE_H
#include "color.h"
#include "compat.h"
#include "envmap.h"
#include "params.h"
#include "path_state.h"
#include "piecewise_constant.h"

// 16 x 32 regions of 11.25 degrees: at 320 x 240 and larger films the cells have the records
// to fill them (8 x 16 left 13% more variance in window_room, 6% in skylight_room; 12 x 24
// half-way: docs/history/results-journal.md). Two sub-bands per column band keep the sub-bands of a
// 1024-wide map 16 columns wide, as four were with 16 column bands.
#define ETK_GUIDE_ROWS 16
#define ETK_GUIDE_COLS 32
#define ETK_GUIDE_REGIONS (ETK_GUIDE_ROWS * ETK_GUIDE_COLS)
#define ETK_GUIDE_SPLITS 2
#define ETK_GUIDE_SUBBANDS (ETK_GUIDE_COLS * ETK_GUIDE_SPLITS)
#define ETK_GUIDE_CELL_FLOATS (ETK_GUIDE_REGIONS + 2)
#define ETK_GUIDE_LIGHT_COUNT (ETK_GUIDE_REGIONS + 1) // within a slot's ETK_GUIDE_CELL_FLOATS
#define ETK_GUIDE_DIR_FLOATS (ETK_GUIDE_REGIONS + 2)
#define ETK_GUIDE_DIR_SHARE (ETK_GUIDE_REGIONS + 1) // within a slot's ETK_GUIDE_DIR_FLOATS

ETK_BEGIN

// Region R's first distribution row (of h), region C's first column (of w); region R ends where
// R + 1 starts. Regions of zero rows (h < ETK_GUIDE_ROWS) have zero mass.
ETK_FN int etk_guide_row_start(int R, int h) {
    return (R * h) / ETK_GUIDE_ROWS;
}
// Sub-band j's first column (of w); column band C is sub-bands SPLITS C ... SPLITS (C + 1) - 1,
// so it starts at (SPLITS C w) / (SPLITS COLS) = (C w) / COLS.
ETK_FN int etk_guide_sub_start(int j, int w) {
    return (j * w) / ETK_GUIDE_SUBBANDS;
}
ETK_FN int etk_guide_col_start(int C, int w) {
    return etk_guide_sub_start(C * ETK_GUIDE_SPLITS, w);
}
// The region holding distribution row r (the largest R with row_start(R) <= r), column c.
ETK_FN int etk_guide_region_row(int r, int h) {
    return ((r + 1) * ETK_GUIDE_ROWS - 1) / h;
}
ETK_FN int etk_guide_region_col(int c, int w) {
    return ((c + 1) * ETK_GUIDE_COLS - 1) / w;
}
ETK_FN int etk_guide_region(EtkEnvMap env, float2 uv) {
    int r = etk_cell_of(uv.y, env.dist_h), c = etk_cell_of(uv.x, env.dist_w);
    return etk_guide_region_row(r, env.dist_h) * ETK_GUIDE_COLS +
           etk_guide_region_col(c, env.dist_w);
}
ETK_FN int etk_guide_row_table(int R, int C, int h) {
    return ETK_GUIDE_REGIONS + C * (h + ETK_GUIDE_ROWS) + etk_guide_row_start(R, h) + R;
}
// Distribution row r's CDF at the sub-band starts (entry ETK_GUIDE_SUBBANDS: its end, 1).
ETK_FN int etk_guide_split_table(int r, int h) {
    return ETK_GUIDE_REGIONS + ETK_GUIDE_COLS * (h + ETK_GUIDE_ROWS) + r * (ETK_GUIDE_SUBBANDS + 1);
}
ETK_FN int etk_guide_regions_size(int h) {
    return etk_guide_split_table(h, h);
}

// The most slots a grid has (host: guide_slots): its keys, slot x ETK_GUIDE_REGIONS + region,
// are then exact as float values (below 2^24), as a continuation record stores them.
#define ETK_GUIDE_MAX_SLOTS (1 << 15)
typedef char
    etk_guide_keys_fit_a_float[ETK_GUIDE_MAX_SLOTS * ETK_GUIDE_REGIONS <= (1 << 24) ? 1 : -1];

// Where slot `cell`'s continuation-guide table starts in guide_cells of `slots` slots.
ETK_FN int etk_guide_dir_offset(int slots, int cell) {
    return slots * ETK_GUIDE_CELL_FLOATS + cell * ETK_GUIDE_DIR_FLOATS;
}

// A cell's key is its grid position and the dominant axis and sign of the geometric normal: one
// of this many normal buckets (etk_guide_cell's nb; the host sizes the grid by it).
#define ETK_GUIDE_NORMAL_BUCKETS 6

// The hash-grid slot of surface point `pos` with geometric normal `n`.
ETK_FN int etk_guide_cell(EtkParams p, float3 pos, float3 n) {
    float3 q = (pos - make_float3(p.guide_origin[0], p.guide_origin[1], p.guide_origin[2])) *
               p.guide_inv_cell;
    int ix = (int)floor(clamp(q.x, -1.0e6f, 1.0e6f));
    int iy = (int)floor(clamp(q.y, -1.0e6f, 1.0e6f));
    int iz = (int)floor(clamp(q.z, -1.0e6f, 1.0e6f));
    float ax = fabs(n.x), ay = fabs(n.y), az = fabs(n.z);
    int axis = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
    float comp = axis == 0 ? n.x : (axis == 1 ? n.y : n.z);
    uint nb = (uint)(2 * axis + (comp < 0.0f ? 1 : 0));
    uint h = (uint)ix * 73856093u ^ (uint)iy * 19349663u ^ (uint)iz * 83492791u ^ nb * 2654435761u;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    return (int)(h & (uint)(p.guide_slots - 1));
}

// p(w) / p_map(w) at map coordinates uv for a vertex in `cell`: Q(R) / M_R (= alpha + (1 - alpha)
// P / M). A region of no mass holds no direction of positive p_map: any factor serves there.
ETK_FN float etk_guide_factor(EtkScene S, EtkParams p, int cell, float2 uv) {
    if (!p.guide_ready)
        return 1.0f;
    int R = etk_guide_region(p.env, uv);
    float M = S.guide_regions[R];
    ETK_GLOBAL const float* cdf = S.guide_cells + cell * ETK_GUIDE_CELL_FLOATS;
    return M > 0.0f ? (cdf[R + 1] - cdf[R]) / M : 1.0f;
}

// The key of a light sample's record (visibility_record.h): its cell's slot and the region of its
// map coordinates uv.
ETK_FN int etk_guide_record_key(EtkEnvMap env, int cell, float2 uv) {
    return cell * ETK_GUIDE_REGIONS + etk_guide_region(env, uv);
}

// The density of the cell's mixture (its table's, ignoring portals) at map coordinates uv: the
// map's times the cell's factor.
ETK_FN float etk_guide_pdf_uv(EtkScene S, EtkParams p, int cell, float2 uv) {
    return etk_env_pdf_uv(S.env_dist, p.env, uv) * etk_guide_factor(S, p, cell, uv);
}
// Its two likely cache misses requested (the map row's CDF entry, the cell's table entry), for a
// batch that asks for many before it reads any.
ETK_FN void etk_guide_pdf_prefetch(EtkScene S, EtkParams p, int cell, float2 uv) {
    int w = p.env.dist_w, h = p.env.dist_h;
    ETK_PREFETCH(etk_dist2d_row_cdf(S.env_dist, w, h, etk_cell_of(uv.y, h)) + etk_cell_of(uv.x, w));
    ETK_PREFETCH(S.guide_cells + cell * ETK_GUIDE_CELL_FLOATS + etk_guide_region(p.env, uv));
}

// The expected number of light samples n in (0, 1] a vertex in `cell` takes: the light sample is
// drawn only when a sample dimension of its own falls below n, and both its MIS weight and the
// escaped continuation's count it as n samples (etk_light_sample_weight, etk_bsdf_sample_weight:
// the multi-sample heuristic with a count of n, Veach), so the light sample counts
// f cos L / (n p) x its weight: unbiased for any n > 0. The host learns n per cell where light
// samples are mostly wasted: cells that face away from every opening of a room, whose shadow rays
// are nearly all blocked while the light arrives through the continuation
// (host/lib/render/visibility_cache.h). 1 until then.
ETK_FN float etk_guide_light_count(EtkScene S, EtkParams p, int cell) {
    return p.guide_ready ? S.guide_cells[cell * ETK_GUIDE_CELL_FLOATS + ETK_GUIDE_LIGHT_COUNT]
                         : 1.0f;
}

// The column of x in a row whose CDF is ccdf and sub-band table split, within column band Rc
// (x in [ccdf[c0], ccdf[c1]]): the last sub-band of the band that has a column and starts at or
// below x, then the last of its columns whose CDF entry is <= x. The same column as the plain
// search clamped to the band, clamp(etk_find_interval(ccdf, w, x), c0, c1 - 1): the sub-band
// starts are entries of the same CDF (tests/kernels/visibility_guide_test.cpp).
// Its first half: the columns [*lo, *hi] of the sub-band x lies in (hi >= lo even in a band of
// no columns, never sampled).
ETK_FN void etk_guide_sub_band(ETK_GLOBAL const float* split, int Rc, int w, float x, int* lo,
                               int* hi) {
    int first = Rc * ETK_GUIDE_SPLITS, c1 = etk_guide_col_start(Rc + 1, w);
    int j = first;
    for (int k = first + 1; k < first + ETK_GUIDE_SPLITS; ++k)
        j = split[k] <= x && etk_guide_sub_start(k, w) < c1 ? k : j;
    *lo = etk_guide_sub_start(j, w);
    *hi = max(etk_guide_sub_start(j + 1, w) - 1, *lo);
}
ETK_FN int etk_guide_column(ETK_GLOBAL const float* ccdf, ETK_GLOBAL const float* split, int Rc,
                            int w, float x) {
    int lo, hi;
    etk_guide_sub_band(split, Rc, w, x, &lo, &hi);
    return etk_find_interval_between(ccdf, lo, hi, x);
}

// The point of the row's CDF u of the way through column band Rc's span [ccdf[c0], ccdf[c1]]
// (split: the row's CDF at the sub-band starts).
ETK_FN float etk_guide_band_point(ETK_GLOBAL const float* split, int Rc, float u) {
    float a = split[Rc * ETK_GUIDE_SPLITS], b = split[(Rc + 1) * ETK_GUIDE_SPLITS];
    return a + clamp(u, 0.0f, ETK_ONE_MINUS_EPS) * (b - a);
}

// Map coordinates drawn inside region R (row band Rr, column band Rc) proportionally to the map,
// from u in [0,1)^2; by inversion of the map's own CDFs restricted to the region.
ETK_FN float2 etk_guide_sample_region(EtkScene S, EtkEnvMap env, int R, float2 u) {
    int w = env.dist_w, h = env.dist_h;
    int Rr = R / ETK_GUIDE_COLS, Rc = R % ETK_GUIDE_COLS;
    int r0 = etk_guide_row_start(Rr, h), nr = etk_guide_row_start(Rr + 1, h) - r0;
    // The row: the region's own row CDF (nr + 1 entries).
    ETK_GLOBAL const float* rcdf = S.guide_regions + etk_guide_row_table(Rr, Rc, h);
    int i = etk_find_interval(rcdf, nr, u.y);
    int row = r0 + i;
    float v = etk_interval_point(rcdf[i], rcdf[i + 1], u.y, row, h);
    // The column: the row's conditional CDF, its span over the band's columns.
    ETK_GLOBAL const float* ccdf = etk_dist2d_row_cdf(S.env_dist, w, h, row);
    ETK_GLOBAL const float* split = S.guide_regions + etk_guide_split_table(row, h);
    float x = etk_guide_band_point(split, Rc, u.x);
    int c = etk_guide_column(ccdf, split, Rc, w, x);
    return make_float2(etk_interval_point(ccdf[c], ccdf[c + 1], x, c, w), v);
}

// (u - a) / (b - a) in [0, 1): where u lies in [a, b), for the next level of a hierarchical warp.
ETK_FN float etk_guide_rescale(float u, float a, float b) {
    return b > a ? clamp((u - a) / (b - a), 0.0f, ETK_ONE_MINUS_EPS) : 0.5f;
}

// The region of a row-major CDF over the ETK_GUIDE_ROWS x ETK_GUIDE_COLS regions that u in
// [0,1)^2 maps to by inversion -- the last band whose start is <= u.y (searching band starts
// cdf[COLS b]), then the last column of it whose start is <= the point u.x of the way through
// the band's mass: never a region of zero probability unless the whole table is -- and, in *t,
// where u lies inside the region, rescaled to [0,1)^2 for the next level.
// Its steps, which the batches also take (etk_guide_pick_batch, below). Both conditions hold for
// a prefix of the (non-decreasing) entries, so binary lifting finds the last of them: 4 + 5 steps
// where a scan of every entry took 15 + 31. ROWS and COLS are powers of two, so the steps sum to
// ROWS - 1 and COLS - 1: no index passes the table. The band: the last whose start is <= y.
ETK_FN int etk_guide_band_step(ETK_GLOBAL const float* cdf, int band, int step, float y) {
    return band + (step & -(int)(cdf[(band + step) * ETK_GUIDE_COLS] <= y));
}
// The column in the band that starts at entry `first` and ends at b1: the last whose start is <=
// x and below the band's end (never a column of zero probability).
ETK_FN int etk_guide_col_step(ETK_GLOBAL const float* cdf, int first, int col, int step, float x,
                              float b1) {
    float c = cdf[first + col + step];
    return col + (step & -((int)(c <= x) & (int)(c < b1)));
}
// Where (u.x, u.y) lies inside region R of the band [b0, b1], x the point u.x of the way through
// the band's mass.
ETK_FN float2 etk_guide_region_offset(ETK_GLOBAL const float* cdf, int R, float x, float y,
                                      float b0, float b1) {
    return make_float2(etk_guide_rescale(x, cdf[R], cdf[R + 1]), etk_guide_rescale(y, b0, b1));
}
// The band's ends b0, b1 in the cell's CDF, and the point ux of the way through its mass.
ETK_FN float etk_guide_band_mass(ETK_GLOBAL const float* cdf, int band, float ux, float* b0,
                                 float* b1) {
    *b0 = cdf[band * ETK_GUIDE_COLS];
    *b1 = cdf[(band + 1) * ETK_GUIDE_COLS];
    return *b0 + ux * (*b1 - *b0);
}
ETK_FN int etk_guide_pick_region(ETK_GLOBAL const float* cdf, float2 u, float2* t) {
    int band = 0;
    for (int step = ETK_GUIDE_ROWS / 2; step > 0; step >>= 1)
        band = etk_guide_band_step(cdf, band, step, u.y);
    int first = band * ETK_GUIDE_COLS;
    float b0, b1;
    float x = etk_guide_band_mass(cdf, band, u.x, &b0, &b1);
    int col = 0;
    for (int step = ETK_GUIDE_COLS / 2; step > 0; step >>= 1)
        col = etk_guide_col_step(cdf, first, col, step, x, b1);
    int R = first + col;
    *t = etk_guide_region_offset(cdf, R, x, u.y, b0, b1);
    return R;
}

// A light sample of the visibility strategy at a vertex in `cell`, from u in [0,1)^2: the region
// by inverting the cell's table, then the map inside the region. pdf: the mixture's, 0 for no
// sample.
// The sample of `cell` at map coordinates uv, drawn there by the two steps above: its direction
// and density, the map's (etk_env_pdf_uv's) times the cell's factor -- the mixture's.
ETK_FN EtkEnvSample etk_guide_sample_at(EtkScene S, EtkParams p, int cell, float2 uv) {
    int w = p.env.dist_w, h = p.env.dist_h;
    EtkEnvSample s = etk_env_sample_at(p.env, uv, etk_pdf_2d(S.env_dist, w, h, uv),
                                       etk_cell_of(uv.y, h), etk_cell_of(uv.x, w));
    s.pdf *= etk_guide_factor(S, p, cell, uv);
    return s;
}

ETK_STRUCT_INLINE_FN EtkEnvSample etk_guide_sample(EtkScene S, EtkParams p, int cell, float2 u) {
    if (!p.guide_ready)
        return etk_env_sample(S.env_dist, p.env, u);
    float2 t;
    int R = etk_guide_pick_region(S.guide_cells + cell * ETK_GUIDE_CELL_FLOATS, u, &t);
    return etk_guide_sample_at(S, p, cell, etk_guide_sample_region(S, p.env, R, t));
}

// A batch's samples of the cells' tables (etk_guide_table_batch, below; the binned and the learned
// techniques' batches: cosine_light.h, portal_guide.h), drawn in steps, each a loop over the
// batch's arrays of scalars, so that both compilers vectorise the searches and the cache misses of
// the cells' tables and the map's rows overlap: etk_guide_sample's own steps per sample, in the
// same order, so the same bits as one at a time. Each search runs step by step across the batch
// with the batch's largest step count: a step larger than a sample's own never moves it
// (etk_interval_step). Sample k's cell table is at gc + tab[k].

// The regions (etk_guide_pick_region): the band, then the column; (tu, tv) where each sample lies
// inside its region.
ETK_FN void etk_guide_pick_batch(ETK_GLOBAL const float* gc, const int* tab, const float* xu,
                                 const float* xv, int n, int* band, int* col, float* tu,
                                 float* tv) {
    float b0[ETK_LIGHT_BATCH], b1[ETK_LIGHT_BATCH], x[ETK_LIGHT_BATCH];
    for (int k = 0; k < n; ++k)
        band[k] = 0;
    for (int step = ETK_GUIDE_ROWS / 2; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k)
            band[k] = etk_guide_band_step(gc + tab[k], band[k], step, xv[k]);
    for (int k = 0; k < n; ++k) {
        x[k] = etk_guide_band_mass(gc + tab[k], band[k], xu[k], &b0[k], &b1[k]);
        col[k] = 0;
    }
    for (int step = ETK_GUIDE_COLS / 2; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k)
            col[k] = etk_guide_col_step(gc + tab[k], band[k] * ETK_GUIDE_COLS, col[k], step, x[k],
                                        b1[k]);
    for (int k = 0; k < n; ++k) {
        float2 t = etk_guide_region_offset(gc + tab[k], band[k] * ETK_GUIDE_COLS + col[k], x[k],
                                           xv[k], b0[k], b1[k]);
        tu[k] = t.x;
        tv[k] = t.y;
    }
}

// The distribution rows inside the regions (etk_guide_sample_region's first half): each band's
// row CDF for its column band, searched as etk_find_interval searches it; v and the row.
ETK_FN void etk_guide_row_batch(ETK_GLOBAL const float* gr, int h, const int* band, const int* col,
                                const float* tv, int n, int* row, float* v) {
    int lo[ETK_LIGHT_BATCH], rows[ETK_LIGHT_BATCH], off[ETK_LIGHT_BATCH];
    int first = 1;
    for (int k = 0; k < n; ++k) {
        row[k] = etk_guide_row_start(band[k], h);
        rows[k] = etk_guide_row_start(band[k] + 1, h) - row[k];
        off[k] = etk_guide_row_table(band[k], col[k], h);
        lo[k] = 0;
        first = max(first, etk_interval_first_step(rows[k]));
    }
    for (int step = first; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k)
            lo[k] = etk_interval_step(gr + off[k], lo[k], step, rows[k] - 1, tv[k]);
    for (int k = 0; k < n; ++k) {
        ETK_GLOBAL const float* rcdf = gr + off[k];
        row[k] += lo[k];
        v[k] = etk_interval_point(rcdf[lo[k]], rcdf[lo[k] + 1], tv[k], row[k], h);
    }
}

// The columns (its second half): each row's conditional CDF over the region's column band, the
// sub-band, then etk_find_interval_between over its columns (etk_guide_column); u.
ETK_FN void etk_guide_column_batch(ETK_GLOBAL const float* dist, ETK_GLOBAL const float* gr, int w,
                                   int h, const int* row, const int* col, const float* tu, int n,
                                   float* u) {
    int lo[ETK_LIGHT_BATCH], hi[ETK_LIGHT_BATCH], off[ETK_LIGHT_BATCH];
    float x[ETK_LIGHT_BATCH];
    int first = 1;
    for (int k = 0; k < n; ++k) {
        ETK_GLOBAL const float* split = gr + etk_guide_split_table(row[k], h);
        x[k] = etk_guide_band_point(split, col[k], tu[k]);
        etk_guide_sub_band(split, col[k], w, x[k], &lo[k], &hi[k]);
        off[k] = (int)(etk_dist2d_row_cdf(dist, w, h, row[k]) - dist);
        first = max(first, etk_interval_first_step_between(hi[k] - lo[k]));
    }
    for (int step = first; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k)
            lo[k] = etk_interval_step(dist + off[k], lo[k], step, hi[k], x[k]);
    for (int k = 0; k < n; ++k) {
        ETK_GLOBAL const float* ccdf = dist + off[k];
        u[k] = etk_interval_point(ccdf[lo[k]], ccdf[lo[k] + 1], x[k], lo[k], w);
    }
}

// The samples of cells cell[0 .. n-1] (p.guide_ready) from (xu[k], xv[k]): map coordinates (u, v),
// direction and density, as etk_guide_sample draws them.
ETK_FN void etk_guide_table_batch(EtkScene S, EtkParams p, const int* cell, const float* xu,
                                  const float* xv, int n, float* u, float* v, float* dx, float* dy,
                                  float* dz, float* pdf) {
    int tab[ETK_LIGHT_BATCH], band[ETK_LIGHT_BATCH], col[ETK_LIGHT_BATCH], row[ETK_LIGHT_BATCH];
    float tu[ETK_LIGHT_BATCH], tv[ETK_LIGHT_BATCH];
    for (int k = 0; k < n; ++k)
        tab[k] = cell[k] * ETK_GUIDE_CELL_FLOATS;
    etk_guide_pick_batch(S.guide_cells, tab, xu, xv, n, band, col, tu, tv);
    etk_guide_row_batch(S.guide_regions, p.env.dist_h, band, col, tv, n, row, v);
    etk_guide_column_batch(S.env_dist, S.guide_regions, p.env.dist_w, p.env.dist_h, row, col, tu, n,
                           u);
    for (int k = 0; k < n; ++k) { // directions and densities
        EtkEnvSample ls = etk_guide_sample_at(S, p, cell[k], make_float2(u[k], v[k]));
        dx[k] = ls.dir.x;
        dy[k] = ls.dir.y;
        dz[k] = ls.dir.z;
        pdf[k] = ls.pdf;
    }
}

// Sample s as entry k of a batch's arrays.
ETK_FN void etk_batch_put(EtkEnvSample s, int k, float* u, float* v, float* dx, float* dy,
                          float* dz, float* pdf) {
    u[k] = s.uv.x;
    v[k] = s.uv.y;
    dx[k] = s.dir.x;
    dy[k] = s.dir.y;
    dz[k] = s.dir.z;
    pdf[k] = s.pdf;
}

// A batch's light samples (map coordinates, direction, density; 0: none) with the map's radiance
// at them, into the slots' light_dir, light_L and light_cell (integrator.h, sample_lights).
ETK_FN void etk_guide_store_batch(EtkScene S, EtkPaths P, EtkParams p, ETK_GLOBAL const int* slots,
                                  const int* cell, int n, float* u, float* v, const float* dx,
                                  const float* dy, const float* dz, const float* pdf) {
    float Lr[ETK_LIGHT_BATCH], Lg[ETK_LIGHT_BATCH], Lb[ETK_LIGHT_BATCH];
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        if (k >= n || !(pdf[k] > 0.0f)) { // no sample: no light, and coordinates lookups can read
            u[k] = 0.0f;
            v[k] = 0.0f;
        }
    etk_env_radiance_batch(S.env_texels, p.env, u, v, Lr, Lg, Lb);
    for (int k = 0; k < n; ++k)
        etk_put_light_sample(P, slots[k], dx[k], dy[k], dz[k], pdf[k], Lr[k], Lg[k], Lb[k],
                             cell[k]);
}

ETK_END

#endif
