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
// loop over the batch's arrays of scalars, so that both compilers vectorise the searches and the
// cache misses of the bins' tables and the map's rows overlap: etk_guide_sample's own steps
// (visibility_guide.h, piecewise_constant.h) per sample, in the same order, so the same bits as
// one at a time. Each search runs step by step across the batch with the batch's largest step
// count: a step larger than a sample's own never moves it (etk_interval_step). Sample k's bin
// table is at gc + tab[k].

// The regions (etk_guide_pick_region): the band, then the column; (tu, tv) where each sample lies
// inside its region.
ETK_FN void etk_cosine_pick_batch(ETK_GLOBAL const float* gc, const int* tab, const float* xu,
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
ETK_FN void etk_cosine_row_batch(ETK_GLOBAL const float* gr, int h, const int* band, const int* col,
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
ETK_FN void etk_cosine_column_batch(ETK_GLOBAL const float* dist, ETK_GLOBAL const float* gr, int w,
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
        for (int k = 0; k < n; ++k) { // directions and densities (etk_guide_sample_at)
            EtkEnvSample ls = etk_guide_sample_at(S, p, max(cell[k], 0), make_float2(u[k], v[k]));
            dx[k] = ls.dir.x;
            dy[k] = ls.dir.y;
            dz[k] = ls.dir.z;
            pdf[k] = ls.pdf;
        }
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
