// Environment-map light: radiance lookup, importance sampling and its solid-angle density
// (paper, Section 3.4). The texels are RGB floats, row-major, row 0 looking up; the distribution
// is a flat 2D piecewise-constant table (piecewise_constant.h) of dist_w x dist_h cells over the
// same lat-long domain. A rotation about the up axis turns map space into world space.
#ifndef ETK_ENVMAP_H
#define ETK_ENVMAP_H
#include "compat.h"
#include "latlong.h"
#include "piecewise_constant.h"

ETK_BEGIN

// Passed by value to kernels: 4-byte members only, so host and device layouts agree.
typedef struct {
    int tex_w, tex_h;   // texel resolution
    int dist_w, dist_h; // sampling distribution resolution
    float scale;        // radiance multiplier
    float rot_cos, rot_sin;
    int has_light; // 0 for an all-black map: sampling returns density 0
} EtkEnvMap;

ETK_FN float3 etk_env_to_world(EtkEnvMap env, float3 d) {
    return make_float3(env.rot_cos * d.x - env.rot_sin * d.z, d.y,
                       env.rot_sin * d.x + env.rot_cos * d.z);
}
ETK_FN float3 etk_world_to_env(EtkEnvMap env, float3 d) {
    return make_float3(env.rot_cos * d.x + env.rot_sin * d.z, d.y,
                       -env.rot_sin * d.x + env.rot_cos * d.z);
}

ETK_FN float3 etk_texel(ETK_GLOBAL const float* texels, int w, int row, int col) {
    ETK_GLOBAL const float* t = texels + 3 * (row * w + col);
    return make_float3(t[0], t[1], t[2]);
}

// The bilinear lookup's four texels: rows r0, r1 and columns c0, c1 (wrapping in longitude) of a
// w x h map, weights tx, ty of the second ones.
typedef struct {
    int r0, r1, c0, c1;
    float tx, ty;
} EtkTexelQuad;
ETK_FN EtkTexelQuad etk_env_quad(int w, int h, float2 uv) {
    EtkTexelQuad q;
    float x = uv.x * (float)w - 0.5f;
    float y = uv.y * (float)h - 0.5f;
    float fx = floor(x), fy = floor(y);
    q.tx = x - fx;
    q.ty = y - fy;
    int c0 = (int)fx % w;
    if (c0 < 0)
        c0 += w;
    q.c0 = c0;
    q.c1 = c0 + 1 == w ? 0 : c0 + 1;
    q.r0 = clamp((int)fy, 0, h - 1);
    q.r1 = clamp((int)fy + 1, 0, h - 1);
    return q;
}
ETK_FN float3 etk_env_blend(ETK_GLOBAL const float* texels, int w, EtkTexelQuad q) {
    float3 top =
        etk_texel(texels, w, q.r0, q.c0) * (1.0f - q.tx) + etk_texel(texels, w, q.r0, q.c1) * q.tx;
    float3 bot =
        etk_texel(texels, w, q.r1, q.c0) * (1.0f - q.tx) + etk_texel(texels, w, q.r1, q.c1) * q.tx;
    return top * (1.0f - q.ty) + bot * q.ty;
}
// Bilinear lookup at (u, v) with texel centres at half-integers: wraps in u, clamps at the poles.
ETK_FN float3 etk_env_lookup_uv(ETK_GLOBAL const float* texels, int w, int h, float2 uv) {
    return etk_env_blend(texels, w, etk_env_quad(w, h, uv));
}

// Radiance arriving from world direction d.
// Map coordinates of world direction d. Callers needing both radiance and density of one
// direction compute this once and use the _uv forms (the inverse mapping costs two atan2).
ETK_FN float2 etk_env_uv(EtkEnvMap env, float3 d) {
    return etk_dir_to_latlong(etk_world_to_env(env, d));
}

ETK_FN float3 etk_env_radiance_uv(ETK_GLOBAL const float* texels, EtkEnvMap env, float2 uv) {
    return etk_env_lookup_uv(texels, env.tex_w, env.tex_h, uv) * env.scale;
}
ETK_FN float3 etk_env_radiance(ETK_GLOBAL const float* texels, EtkEnvMap env, float3 d) {
    return etk_env_radiance_uv(texels, env, etk_env_uv(env, d));
}

// Solid-angle density of sampling world direction d (at map coordinates uv).
ETK_FORCE_INLINE_FN float etk_env_pdf_uv(ETK_GLOBAL const float* dist, EtkEnvMap env, float2 uv) {
    if (!env.has_light)
        return 0.0f;
    return etk_latlong_pdf_to_solid_angle(etk_pdf_2d(dist, env.dist_w, env.dist_h, uv), uv.y);
}
ETK_FN float etk_env_pdf(ETK_GLOBAL const float* dist, EtkEnvMap env, float3 d) {
    return etk_env_pdf_uv(dist, env, etk_env_uv(env, d));
}

typedef struct {
    float3 dir;   // world space
    float pdf;    // solid angle; 0 means no sample (all-black map)
    float2 uv;    // lat-long coordinates in map space
    int row, col; // distribution cell
} EtkEnvSample;

// The sample at map coordinates uv (distribution cell row, col) drawn with density pdf_uv on the
// unit square: its world direction and solid-angle density, from one sin/cos of theta. Every
// technique that samples the map ends here (etk_env_sample; visibility_guide.h).
ETK_FN EtkEnvSample etk_env_sample_at(EtkEnvMap env, float2 uv, float pdf_uv, int row, int col) {
    EtkEnvSample s;
    s.uv = uv;
    s.row = row;
    s.col = col;
    float2 theta = etk_sincospi(uv.y);
    s.dir = etk_env_to_world(env, etk_latlong_dir(uv.x, theta.y, theta.x));
    s.pdf = env.has_light ? etk_latlong_pdf_to_solid_angle_sin(pdf_uv, theta.x) : 0.0f;
    return s;
}

ETK_FN EtkEnvSample etk_env_sample(ETK_GLOBAL const float* dist, EtkEnvMap env, float2 xi) {
    float pdf_uv;
    int row, col;
    float2 uv = etk_sample_2d(dist, env.dist_w, env.dist_h, xi, &pdf_uv, &row, &col);
    return etk_env_sample_at(env, uv, pdf_uv, row, col);
}

// Light samples drawn ETK_LIGHT_BATCH at a time (the sample_lights stage, integrator.h). One
// sample is a chain of dependent loads -- the row's guide entry and CDF line, then the column's --
// which miss the cache at random rows of a large map; a core overlaps the chains of independent
// samples only as far as its reorder window reaches, about one sample of shade-stage code.
// Interleaving the steps of B samples (for the rows, then the columns: all guide ranges, then the
// first CDF entries of every range -- the columns' prefetched, then plain loads, no branch between
// them -- then all answers; then the directions) puts B chains in flight at once: the column
// search's branch mispredicts now and then, and each misprediction would otherwise restart the
// loads behind it. The same functions in the same order per sample as etk_env_sample, so the same
// bits. B = 32: window_room (mis, 320 x 240, native), the shade stage and this one together 18%
// below the shade stage alone, against 10% / 16% / 18% / 16% for B = 8 / 16 / 32 / 64
// (tools/bench/README.md). One constant for the host (which launches one work-item per batch) and
// the device.
#define ETK_LIGHT_BATCH 32
ETK_FN void etk_env_sample_batch(ETK_GLOBAL const float* dist, EtkEnvMap env, const float2* xi,
                                 EtkEnvSample* out) {
    int w = env.dist_w, h = env.dist_h;
    int row[ETK_LIGHT_BATCH], col[ETK_LIGHT_BATCH], lo[ETK_LIGHT_BATCH], hi[ETK_LIGHT_BATCH];
    int far[ETK_LIGHT_BATCH];
    float u[ETK_LIGHT_BATCH], v[ETK_LIGHT_BATCH], pu[ETK_LIGHT_BATCH], pv[ETK_LIGHT_BATCH];
    float3 head[ETK_LIGHT_BATCH];
    ETK_GLOBAL const float* mcdf = dist + etk_dist2d_marginal_cdf(h);
    ETK_GLOBAL const float* mguide = dist + etk_dist2d_marginal_guide(w, h);
    // Rows: the marginal's guide ranges, their first entries, the answers.
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        etk_guide_range(mguide, h, xi[k].y, &lo[k], &hi[k]);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        head[k] = etk_interval_head(mcdf, h, lo[k]);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        far[k] = etk_interval_beyond_head(lo[k], hi[k], head[k], xi[k].y);
        row[k] = etk_interval_in_head(lo[k], hi[k], head[k], xi[k].y);
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        if (far[k])
            row[k] = etk_find_interval_between(mcdf, lo[k] + 3, hi[k], xi[k].y);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        int cell;
        v[k] = etk_sample_1d_in(mcdf, h, row[k], xi[k].y, &pv[k], &cell);
    }
    // Columns: the same steps in each row's conditional.
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        etk_guide_range(etk_dist2d_row_guide(dist, w, h, row[k]), w, xi[k].x, &lo[k], &hi[k]);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) // all of them requested before any is waited for
        ETK_PREFETCH(etk_dist2d_row_cdf(dist, w, h, row[k]) + lo[k] + 1);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        head[k] = etk_interval_head(etk_dist2d_row_cdf(dist, w, h, row[k]), w, lo[k]);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        far[k] = etk_interval_beyond_head(lo[k], hi[k], head[k], xi[k].x);
        col[k] = etk_interval_in_head(lo[k], hi[k], head[k], xi[k].x);
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        if (far[k])
            col[k] = etk_find_interval_between(etk_dist2d_row_cdf(dist, w, h, row[k]), lo[k] + 3,
                                               hi[k], xi[k].x);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        int cell;
        u[k] = etk_sample_1d_in(etk_dist2d_row_cdf(dist, w, h, row[k]), w, col[k], xi[k].x, &pu[k],
                                &cell);
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        out[k] = etk_env_sample_at(env, make_float2(u[k], v[k]), pv[k] * pu[k], row[k], col[k]);
}

// The radiance of a batch's samples (etk_env_radiance_uv's bits), their texels' lines requested
// for the whole batch before any is read: the shade stage would otherwise miss on each.
ETK_FN void etk_env_radiance_batch(ETK_GLOBAL const float* texels, EtkEnvMap env,
                                   const EtkEnvSample* s, float3* L) {
    EtkTexelQuad q[ETK_LIGHT_BATCH];
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        q[k] = etk_env_quad(env.tex_w, env.tex_h, s[k].uv);
        ETK_PREFETCH(texels + 3 * (q[k].r0 * env.tex_w + q[k].c0));
        ETK_PREFETCH(texels + 3 * (q[k].r1 * env.tex_w + q[k].c0));
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        L[k] = etk_env_blend(texels, env.tex_w, q[k]) * env.scale;
}

ETK_END

#endif
