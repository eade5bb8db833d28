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

// The light samples of the paths in slots[0 .. n-1] (n <= ETK_LIGHT_BATCH), of bins cell[k] (-1:
// the full map), from (xu[k], xv[k]), into light_dir, light_L and light_cell: etk_guide_sample's
// steps, each over the batch, so that the cache misses of the bins' tables and the map's rows
// overlap -- the same bits as etk_guide_sample one at a time.
ETK_FN void etk_cosine_light_batch(EtkScene S, EtkPaths P, EtkParams p, ETK_GLOBAL const int* slots,
                                   const int* cell, const float* xu, const float* xv, int n) {
    int R[ETK_LIGHT_BATCH];
    float2 t[ETK_LIGHT_BATCH], uv[ETK_LIGHT_BATCH];
    for (int k = 0; k < n; ++k)
        R[k] = cell[k] >= 0 ? etk_guide_pick_region(S.guide_cells + cell[k] * ETK_GUIDE_CELL_FLOATS,
                                                    make_float2(xu[k], xv[k]), &t[k])
                            : 0;
    for (int k = 0; k < n; ++k)
        uv[k] =
            cell[k] >= 0 ? etk_guide_sample_region(S, p.env, R[k], t[k]) : make_float2(0.0f, 0.0f);
    for (int k = 0; k < n; ++k) {
        EtkEnvSample ls = cell[k] >= 0
                              ? etk_guide_sample_at(S, p, cell[k], uv[k])
                              : etk_env_sample(S.env_dist, p.env, make_float2(xu[k], xv[k]));
        uv[k] = ls.pdf > 0.0f ? ls.uv : make_float2(-1.0f, -1.0f);
        P.light_dir[slots[k]] = etk_f4(ls.dir, ls.pdf);
    }
    for (int k = 0; k < n; ++k) { // the texels, last: a loop of lookups alone
        P.light_L[slots[k]] =
            etk_f4(uv[k].x >= 0.0f ? etk_env_radiance_uv(S.env_texels, p.env, uv[k])
                                   : make_float3(0.0f, 0.0f, 0.0f),
                   0.0f);
        P.light_cell[slots[k]] = cell[k];
    }
}

ETK_END

#endif
