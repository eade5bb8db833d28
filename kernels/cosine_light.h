// The binned technique (ETK_LIGHT_BINNED, the cosine strategy's first vertex): a light sample
// drawn from the map times a bound of the clamped cosine to any normal of the vertex's normal bin
// (normal_bins.h). Its tables sit in the visibility tables' layout (guide_cells, one slot per bin;
// host/lib/prepare/cosine_tables.h), so sampling and density are the learned technique's
// (visibility_guide.h) with the bin for a cell: prepared once with the map, never learned.
#ifndef ETK_COSINE_LIGHT_H
#define ETK_COSINE_LIGHT_H
#include "bsdf.h"
#include "compat.h"
#include "normal_bins.h"
#include "params.h"
#include "path_state.h"
#include "surface.h"
#include "visibility_guide.h"

ETK_BEGIN

// The table of a vertex with shading normal ns, its bin's; -1 at a dielectric, lit from both
// sides, which takes the full map instead (etk_light_source).
ETK_FN int etk_cosine_cell(EtkParams p, EtkMaterial m, float3 ns) {
    return etk_bsdf_is_dielectric(m) ? -1 : p.bin_cell_base + etk_normal_bin(ns);
}

ETK_FN float etk_cosine_light_pdf(EtkScene S, EtkParams p, int cell, float2 uv) {
    return etk_env_pdf_uv(S.env_dist, p.env, uv) * etk_guide_factor(S, p, cell, uv);
}

// The binned light samples of a batch, drawn by etk_cosine_light_batch (below) in steps, each a
// loop over the batch's arrays of scalars, so that both compilers vectorise them and the cache
// misses of the bins' tables and the map's rows overlap: etk_guide_sample's operations per sample,
// in the same order, so the same bits as one at a time. Each search runs step by step across the
// batch with the batch's largest step count: a step larger than a sample's own never moves it
// (etk_find_interval, etk_find_interval_between). Sample k's bin table is at gc + tab[k].

// The regions (etk_guide_pick_region): the band, then the column, by binary lifting; (tu, tv)
// where each sample lies inside its region.
ETK_FN void etk_cosine_pick_batch(ETK_GLOBAL const float* gc, const int* tab, const float* xu,
                                  const float* xv, int n, int* band, int* col, float* tu,
                                  float* tv) {
    float b0[ETK_LIGHT_BATCH], b1[ETK_LIGHT_BATCH], x[ETK_LIGHT_BATCH];
    for (int k = 0; k < n; ++k)
        band[k] = 0;
    for (int step = ETK_GUIDE_ROWS / 2; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k)
            band[k] += step & -(int)(gc[tab[k] + (band[k] + step) * ETK_GUIDE_COLS] <= xv[k]);
    for (int k = 0; k < n; ++k) {
        int first = tab[k] + band[k] * ETK_GUIDE_COLS;
        b0[k] = gc[first];
        b1[k] = gc[first + ETK_GUIDE_COLS];
        x[k] = b0[k] + xu[k] * (b1[k] - b0[k]);
        col[k] = 0;
    }
    for (int step = ETK_GUIDE_COLS / 2; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k) {
            float c = gc[tab[k] + band[k] * ETK_GUIDE_COLS + col[k] + step];
            col[k] += step & -((int)(c <= x[k]) & (int)(c < b1[k]));
        }
    for (int k = 0; k < n; ++k) {
        int R = tab[k] + band[k] * ETK_GUIDE_COLS + col[k];
        tu[k] = etk_guide_rescale(x[k], gc[R], gc[R + 1]);
        tv[k] = etk_guide_rescale(xv[k], b0[k], b1[k]);
    }
}

// The distribution rows inside the regions (etk_guide_sample_region's first half): each band's
// row CDF for its column band, searched as etk_find_interval searches it; v and the row.
ETK_FN void etk_cosine_row_batch(ETK_GLOBAL const float* gr, int h, const int* band, const int* col,
                                 const float* tv, int n, int* row, float* v) {
    int lo[ETK_LIGHT_BATCH], rows[ETK_LIGHT_BATCH], off[ETK_LIGHT_BATCH];
    int first = 1;
    for (int k = 0; k < n; ++k) {
        row[k] = etk_guide_row_start(band[k], h);
        rows[k] = etk_guide_row_start(band[k] + 1, h) - row[k];
        off[k] = etk_guide_row_table(band[k], col[k], h);
        lo[k] = 0;
        while (2 * first < rows[k])
            first *= 2;
    }
    for (int step = first; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k) {
            int mid = lo[k] + step;
            float c = gr[off[k] + min(mid, rows[k] - 1)];
            lo[k] += step & -((int)(mid < rows[k]) & (int)(c <= tv[k]));
        }
    for (int k = 0; k < n; ++k) {
        ETK_GLOBAL const float* rcdf = gr + off[k];
        row[k] += lo[k];
        v[k] = etk_interval_point(rcdf[lo[k]], rcdf[lo[k] + 1], tv[k], row[k], h);
    }
}

// The columns (its second half): each row's conditional CDF over the region's column band
// (etk_guide_column): the sub-band, then etk_find_interval_between over its columns; u.
ETK_FN void etk_cosine_column_batch(ETK_GLOBAL const float* dist, ETK_GLOBAL const float* gr, int w,
                                    int h, const int* row, const int* col, const float* tu, int n,
                                    float* u) {
    int lo[ETK_LIGHT_BATCH], hi[ETK_LIGHT_BATCH], off[ETK_LIGHT_BATCH];
    float x[ETK_LIGHT_BATCH];
    int first = 1;
    for (int k = 0; k < n; ++k) {
        ETK_GLOBAL const float* split = gr + etk_guide_split_table(row[k], h);
        float a = split[col[k] * ETK_GUIDE_SPLITS], b = split[(col[k] + 1) * ETK_GUIDE_SPLITS];
        x[k] = a + clamp(tu[k], 0.0f, ETK_ONE_MINUS_EPS) * (b - a);
        int j0 = col[k] * ETK_GUIDE_SPLITS, c1 = etk_guide_col_start(col[k] + 1, w), j = j0;
        for (int i = j0 + 1; i < j0 + ETK_GUIDE_SPLITS; ++i)
            j = split[i] <= x[k] && etk_guide_sub_start(i, w) < c1 ? i : j;
        lo[k] = etk_guide_sub_start(j, w);
        hi[k] = max(etk_guide_sub_start(j + 1, w) - 1, lo[k]);
        off[k] = (int)(etk_dist2d_row_cdf(dist, w, h, row[k]) - dist);
        while (2 * first <= hi[k] - lo[k])
            first *= 2;
    }
    for (int step = first; step > 0; step >>= 1)
        for (int k = 0; k < n; ++k) {
            int mid = lo[k] + step;
            float c = dist[off[k] + min(mid, hi[k])];
            lo[k] += step & -((int)(mid <= hi[k]) & (int)(c <= x[k]));
        }
    for (int k = 0; k < n; ++k) {
        ETK_GLOBAL const float* ccdf = dist + off[k];
        u[k] = etk_interval_point(ccdf[lo[k]], ccdf[lo[k] + 1], x[k], lo[k], w);
    }
}

// The directions and densities at (u, v) (etk_guide_sample_at): the map's density times the bin's
// factor Q(R) / M_R.
ETK_FN void etk_cosine_density_batch(ETK_GLOBAL const float* dist, ETK_GLOBAL const float* gc,
                                     ETK_GLOBAL const float* gr, EtkEnvMap env, const int* tab,
                                     const float* u, const float* v, int n, float* dx, float* dy,
                                     float* dz, float* pdf) {
    int w = env.dist_w, h = env.dist_h;
    for (int k = 0; k < n; ++k) {
        int r = etk_cell_of(v[k], h), c = etk_cell_of(u[k], w);
        float pdf_uv = etk_interval_density(dist + etk_dist2d_marginal_cdf(h), h, r) *
                       etk_interval_density(etk_dist2d_row_cdf(dist, w, h, r), w, c);
        float2 theta = etk_sincospi(v[k]);
        float3 d = etk_env_sample_dir(env, u[k], theta);
        dx[k] = d.x;
        dy[k] = d.y;
        dz[k] = d.z;
        int R = etk_guide_region_row(r, h) * ETK_GUIDE_COLS + etk_guide_region_col(c, w);
        float M = gr[R];
        float f = M > 0.0f ? (gc[tab[k] + R + 1] - gc[tab[k] + R]) / M : 1.0f;
        pdf[k] = etk_env_sample_pdf(env, pdf_uv, theta.x) * f;
    }
}

// The light samples of the paths in slots[0 .. n-1] (n <= ETK_LIGHT_BATCH), of bins cell[k] (-1:
// the full map), from (xu[k], xv[k]), into light_dir, light_L and light_cell. A full-map sample
// goes through the steps with the first slot's table of guide_cells (always there; every read
// stays in bounds whatever it holds) and is drawn again, alone, at the end (rough dielectrics:
// rare).
ETK_FN void etk_cosine_light_batch(EtkScene S, EtkPaths P, EtkParams p, ETK_GLOBAL const int* slots,
                                   const int* cell, const float* xu, const float* xv, int n) {
    int tab[ETK_LIGHT_BATCH], band[ETK_LIGHT_BATCH], col[ETK_LIGHT_BATCH], row[ETK_LIGHT_BATCH];
    float tu[ETK_LIGHT_BATCH], tv[ETK_LIGHT_BATCH], u[ETK_LIGHT_BATCH], v[ETK_LIGHT_BATCH];
    float pdf[ETK_LIGHT_BATCH], dx[ETK_LIGHT_BATCH], dy[ETK_LIGHT_BATCH], dz[ETK_LIGHT_BATCH];
    float Lr[ETK_LIGHT_BATCH], Lg[ETK_LIGHT_BATCH], Lb[ETK_LIGHT_BATCH];
    int binned = 0;
    for (int k = 0; k < n; ++k) {
        binned |= cell[k] >= 0;
        tab[k] = max(cell[k], 0) * ETK_GUIDE_CELL_FLOATS;
    }
    for (int k = n; k < ETK_LIGHT_BATCH; ++k) { // coordinates the radiance's lookups can read
        u[k] = 0.0f;
        v[k] = 0.0f;
    }
    if (binned) { // the bins' tables exist
        etk_cosine_pick_batch(S.guide_cells, tab, xu, xv, n, band, col, tu, tv);
        etk_cosine_row_batch(S.guide_regions, p.env.dist_h, band, col, tv, n, row, v);
        etk_cosine_column_batch(S.env_dist, S.guide_regions, p.env.dist_w, p.env.dist_h, row, col,
                                tu, n, u);
        etk_cosine_density_batch(S.env_dist, S.guide_cells, S.guide_regions, p.env, tab, u, v, n,
                                 dx, dy, dz, pdf);
    }
    for (int k = 0; k < n; ++k)
        if (cell[k] < 0) {
            EtkEnvSample ls = etk_env_sample(S.env_dist, p.env, make_float2(xu[k], xv[k]));
            u[k] = ls.uv.x;
            v[k] = ls.uv.y;
            dx[k] = ls.dir.x;
            dy[k] = ls.dir.y;
            dz[k] = ls.dir.z;
            pdf[k] = ls.pdf;
        }
    for (int k = 0; k < n; ++k)
        if (!(pdf[k] > 0.0f)) { // no sample: no light, and coordinates the lookups can read
            u[k] = 0.0f;
            v[k] = 0.0f;
        }
    etk_env_radiance_batch(S.env_texels, p.env, u, v, Lr, Lg, Lb);
    for (int k = 0; k < n; ++k) {
        int lit = pdf[k] > 0.0f;
        P.light_dir[slots[k]] = make_float4(dx[k], dy[k], dz[k], pdf[k]);
        P.light_L[slots[k]] =
            make_float4(lit ? Lr[k] : 0.0f, lit ? Lg[k] : 0.0f, lit ? Lb[k] : 0.0f, 0.0f);
        P.light_cell[slots[k]] = cell[k];
    }
}

ETK_END

#endif
