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
    return etk_guide_pdf_uv(S, p, cell, uv);
}

// The light samples of the paths in slots[0 .. n-1] (n <= ETK_LIGHT_BATCH), of bins cell[k] (-1:
// the full map), from (xu[k], xv[k]), into light_dir, light_L and light_cell. A full-map sample
// goes through the steps with the first slot's table of guide_cells (always there; every read
// stays in bounds whatever it holds) and is drawn again, alone, at the end (rough dielectrics:
// rare).
ETK_FN void etk_cosine_light_batch(EtkScene S, EtkPaths P, EtkParams p, ETK_GLOBAL const int* slots,
                                   const int* cell, const float* xu, const float* xv, int n) {
    int tab[ETK_LIGHT_BATCH];
    float u[ETK_LIGHT_BATCH], v[ETK_LIGHT_BATCH], pdf[ETK_LIGHT_BATCH];
    float dx[ETK_LIGHT_BATCH], dy[ETK_LIGHT_BATCH], dz[ETK_LIGHT_BATCH];
    int binned = 0;
    for (int k = 0; k < n; ++k) {
        binned |= cell[k] >= 0;
        tab[k] = max(cell[k], 0);
    }
    if (binned) // the bins' tables exist
        etk_guide_table_batch(S, p, tab, xu, xv, n, u, v, dx, dy, dz, pdf);
    for (int k = 0; k < n; ++k)
        if (cell[k] < 0)
            etk_batch_put(etk_env_sample(S.env_dist, p.env, make_float2(xu[k], xv[k])), k, u, v, dx,
                          dy, dz, pdf);
    etk_guide_store_batch(S, P, p, slots, cell, n, u, v, dx, dy, dz, pdf);
}

ETK_END

#endif
