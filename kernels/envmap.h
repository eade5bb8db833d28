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
    // The black mask's blocks across and down (host/lib/prepare/env_black_mask.h); 0: the map has
    // no black block, and nothing asks.
    int black_w, black_h;
    // The solid angle (sr) of the blocks the mask leaves clear: where the map's light can come
    // from (read only where black_w > 0).
    float lit_sr;
} EtkEnvMap;

ETK_FN float3 etk_env_to_world(EtkEnvMap env, float3 d) {
    return make_float3(env.rot_cos * d.x - env.rot_sin * d.z, d.y,
                       env.rot_sin * d.x + env.rot_cos * d.z);
}
ETK_FN float3 etk_world_to_env(EtkEnvMap env, float3 d) {
    return make_float3(env.rot_cos * d.x + env.rot_sin * d.z, d.y,
                       -env.rot_sin * d.x + env.rot_cos * d.z);
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
// One channel c of the bilinear blend; etk_env_blend is the three (the same operations as one
// float3 expression: component-wise). Scalar, so that a batch's loop over it vectorises.
ETK_FN float etk_env_blend_channel(ETK_GLOBAL const float* texels, int w, EtkTexelQuad q, int c) {
    float top = texels[3 * (q.r0 * w + q.c0) + c] * (1.0f - q.tx) +
                texels[3 * (q.r0 * w + q.c1) + c] * q.tx;
    float bot = texels[3 * (q.r1 * w + q.c0) + c] * (1.0f - q.tx) +
                texels[3 * (q.r1 * w + q.c1) + c] * q.tx;
    return top * (1.0f - q.ty) + bot * q.ty;
}
ETK_FN float3 etk_env_blend(ETK_GLOBAL const float* texels, int w, EtkTexelQuad q) {
    return make_float3(etk_env_blend_channel(texels, w, q, 0),
                       etk_env_blend_channel(texels, w, q, 1),
                       etk_env_blend_channel(texels, w, q, 2));
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

ETK_STRUCT_INLINE_FN float3 etk_env_radiance_uv(ETK_GLOBAL const float* texels, EtkEnvMap env,
                                                float2 uv) {
    return etk_env_lookup_uv(texels, env.tex_w, env.tex_h, uv) * env.scale;
}
ETK_FN float3 etk_env_radiance(ETK_GLOBAL const float* texels, EtkEnvMap env, float3 d) {
    return etk_env_radiance_uv(texels, env, etk_env_uv(env, d));
}

// Whether the radiance at map coordinates uv is zero for certain: the black mask's bit of the
// ETK_ENV_BLACK_BLOCK-texel block that holds uv, set by the host only where that block and its
// eight neighbours are all zero, so that the bilinear lookup's four texels (within one texel of
// uv's) are zero too. 0 where unsure (coordinates out of range included).
#define ETK_ENV_BLACK_BLOCK 8
ETK_FN int etk_env_black_uv(ETK_GLOBAL const int* mask, EtkEnvMap env, float2 uv) {
    if (!(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f))
        return 0;
    int bx = min((int)(uv.x * (float)env.tex_w) / ETK_ENV_BLACK_BLOCK, env.black_w - 1);
    int by = min((int)(uv.y * (float)env.tex_h) / ETK_ENV_BLACK_BLOCK, env.black_h - 1);
    int bit = by * env.black_w + bx;
    return (mask[bit >> 5] >> (bit & 31)) & 1;
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

// Its two halves: the world direction at longitude coordinate u and (sin, cos) theta, and the
// solid-angle density from pdf_uv and sin theta.
ETK_FN float3 etk_env_sample_dir(EtkEnvMap env, float u, float2 theta) {
    return etk_env_to_world(env, etk_latlong_dir(u, theta.y, theta.x));
}
ETK_FN float etk_env_sample_pdf(EtkEnvMap env, float pdf_uv, float sin_theta) {
    return env.has_light ? etk_latlong_pdf_to_solid_angle_sin(pdf_uv, sin_theta) : 0.0f;
}

// The sample at map coordinates uv (distribution cell row, col) drawn with density pdf_uv on the
// unit square: its world direction and solid-angle density, from one sin/cos of theta. Every
// technique that samples the map ends here (etk_env_sample; visibility_guide.h).
ETK_STRUCT_INLINE_FN EtkEnvSample etk_env_sample_at(EtkEnvMap env, float2 uv, float pdf_uv, int row,
                                                    int col) {
    EtkEnvSample s;
    s.uv = uv;
    s.row = row;
    s.col = col;
    float2 theta = etk_sincospi(uv.y);
    s.dir = etk_env_sample_dir(env, uv.x, theta);
    s.pdf = etk_env_sample_pdf(env, pdf_uv, theta.x);
    return s;
}

ETK_STRUCT_INLINE_FN EtkEnvSample etk_env_sample(ETK_GLOBAL const float* dist, EtkEnvMap env,
                                                 float2 xi) {
    float pdf_uv;
    int row, col;
    float2 uv = etk_sample_2d(dist, env.dist_w, env.dist_h, xi, &pdf_uv, &row, &col);
    return etk_env_sample_at(env, uv, pdf_uv, row, col);
}

// Light samples drawn ETK_LIGHT_BATCH at a time (the sample_lights stage, integrator.h). One
// sample is a chain of dependent loads -- the row's guide entry and CDF line, then the column's --
// which miss the cache at random rows of a large map; a core overlaps the chains of independent
// samples only as far as its reorder window reaches, about one sample of shade-stage code.
// Interleaving the steps of B samples (etk_sample_1d_batch for the rows, then the columns: all
// guide ranges, then the first CDF entries of every range -- prefetched, then plain loads, no
// branch between them -- then all answers; then the directions) puts B chains in flight at once:
// the column search's branch mispredicts now and then, and each misprediction would otherwise
// restart the loads behind it. The same functions in the same order per sample as etk_env_sample,
// so the same bits. B = 32: window_room (mis, 320 x 240, native), the shade stage and this one
// together 18% below the shade stage alone, against 10% / 16% / 18% / 16% for B = 8 / 16 / 32 / 64
// (docs/history/bench-journal.md). One constant for the host (which launches one work-item per
// batch) and the device.
#define ETK_LIGHT_BATCH 32
// Every loop runs over arrays of scalars: LLVM (PoCL) vectorises no loop that holds a
// vector-typed value (a float2 or float3), GCC (native) splits those itself.
// One 1D inversion per sample of a batch, etk_sample_1d_in(etk_find_interval_guided(...))'s steps
// for all of them at once: sample k inverts the CDF at dist + cdf[k] (n intervals; its guide at
// dist + guide[k]) at x[k]. The guide ranges, then the first CDF entries of every range (requested,
// then loaded), the answers, the rare longer search, the points.
ETK_FN void etk_sample_1d_batch(ETK_GLOBAL const float* dist, const int* cdf, const int* guide,
                                int n, const float* x, float* point, float* density, int* cell) {
    int lo[ETK_LIGHT_BATCH], hi[ETK_LIGHT_BATCH], far[ETK_LIGHT_BATCH];
    float h0[ETK_LIGHT_BATCH], h1[ETK_LIGHT_BATCH], h2[ETK_LIGHT_BATCH]; // etk_interval_head
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        etk_guide_range(dist + guide[k], n, x[k], &lo[k], &hi[k]);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) // all of them requested before any is waited for
        ETK_PREFETCH(dist + cdf[k] + lo[k] + 1);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        h0[k] = etk_interval_head_entry(dist + cdf[k], n, lo[k], 0);
        h1[k] = etk_interval_head_entry(dist + cdf[k], n, lo[k], 1);
        h2[k] = etk_interval_head_entry(dist + cdf[k], n, lo[k], 2);
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        far[k] = etk_interval_beyond_head(lo[k], hi[k], h2[k], x[k]);
        cell[k] = etk_interval_in_head(lo[k], hi[k], h0[k], h1[k], x[k]);
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        if (far[k])
            cell[k] = etk_find_interval_between(dist + cdf[k], lo[k] + 3, hi[k], x[k]);
    // etk_sample_1d_in's steps, its two CDF entries gathered first: GCC then vectorises the
    // density and the point (as one etk_sample_1d_in per sample it kept them scalar).
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        h0[k] = dist[cdf[k] + cell[k]];
        h1[k] = dist[cdf[k] + cell[k] + 1];
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        density[k] = etk_interval_density_between(h0[k], h1[k], n);
    // For a power-of-two n (most maps) the point's steps as one vectorisable loop; the general
    // path's fixed-count corrections keep GCC from vectorising the loop that holds both.
    if (etk_is_pow2(n)) {
        float inv = etk_inv_pow2((uint)n);
        for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
            point[k] = etk_cell_coordinate_pow2(cell[k], etk_interval_t(h0[k], h1[k], x[k]), inv);
    } else {
        for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
            point[k] = etk_interval_point(h0[k], h1[k], x[k], cell[k], n);
    }
}
// The first half of a batch of map samples: map coordinates (u, v), their density on the square
// and the cell, from the sample values (xu, xv): the rows from the marginal, then the columns
// from each sample's row (etk_sample_2d's steps).
ETK_FN void etk_env_sample_batch_uv(ETK_GLOBAL const float* dist, EtkEnvMap env, const float* xu,
                                    const float* xv, float* u, float* v, float* pdf_uv, int* row,
                                    int* col) {
    int w = env.dist_w, h = env.dist_h;
    int cdf[ETK_LIGHT_BATCH], guide[ETK_LIGHT_BATCH];
    float pu[ETK_LIGHT_BATCH], pv[ETK_LIGHT_BATCH];
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        cdf[k] = etk_dist2d_marginal_cdf(h);
        guide[k] = etk_dist2d_marginal_guide(w, h);
    }
    etk_sample_1d_batch(dist, cdf, guide, h, xv, v, pv, row);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        cdf[k] = (int)(etk_dist2d_row_cdf(dist, w, h, row[k]) - dist);
        guide[k] = (int)(etk_dist2d_row_guide(dist, w, h, row[k]) - dist);
    }
    etk_sample_1d_batch(dist, cdf, guide, w, xu, u, pu, col);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k)
        pdf_uv[k] = pv[k] * pu[k];
}
// The second half: etk_env_sample_at's steps (direction and solid-angle density, as arrays).
ETK_FN void etk_env_sample_batch_dir(EtkEnvMap env, const float* u, const float* v,
                                     const float* pdf_uv, float* dx, float* dy, float* dz,
                                     float* pdf) {
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        float2 theta = etk_sincospi(v[k]);
        float3 d = etk_env_sample_dir(env, u[k], theta);
        dx[k] = d.x;
        dy[k] = d.y;
        dz[k] = d.z;
        pdf[k] = etk_env_sample_pdf(env, pdf_uv[k], theta.x);
    }
}
// Both, as EtkEnvSamples: etk_env_sample's values for each (tests/kernels/cdf_guide_test.cpp).
ETK_FN void etk_env_sample_batch(ETK_GLOBAL const float* dist, EtkEnvMap env, const float* xu,
                                 const float* xv, EtkEnvSample* out) {
    float u[ETK_LIGHT_BATCH], v[ETK_LIGHT_BATCH], pdf_uv[ETK_LIGHT_BATCH];
    float dx[ETK_LIGHT_BATCH], dy[ETK_LIGHT_BATCH], dz[ETK_LIGHT_BATCH], pdf[ETK_LIGHT_BATCH];
    int row[ETK_LIGHT_BATCH], col[ETK_LIGHT_BATCH];
    etk_env_sample_batch_uv(dist, env, xu, xv, u, v, pdf_uv, row, col);
    etk_env_sample_batch_dir(env, u, v, pdf_uv, dx, dy, dz, pdf);
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        out[k].dir = make_float3(dx[k], dy[k], dz[k]);
        out[k].pdf = pdf[k];
        out[k].uv = make_float2(u[k], v[k]);
        out[k].row = row[k];
        out[k].col = col[k];
    }
}

// The radiance of a batch's samples (etk_env_radiance_uv's bits) as three arrays, their texels'
// lines requested for the whole batch before any is read: the shade stage would otherwise miss
// on each.
ETK_FN void etk_env_radiance_batch(ETK_GLOBAL const float* texels, EtkEnvMap env, const float* u,
                                   const float* v, float* r, float* g, float* b) {
    int r0[ETK_LIGHT_BATCH], r1[ETK_LIGHT_BATCH], c0[ETK_LIGHT_BATCH], c1[ETK_LIGHT_BATCH];
    float tx[ETK_LIGHT_BATCH], ty[ETK_LIGHT_BATCH];
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        EtkTexelQuad q = etk_env_quad(env.tex_w, env.tex_h, make_float2(u[k], v[k]));
        r0[k] = q.r0;
        r1[k] = q.r1;
        c0[k] = q.c0;
        c1[k] = q.c1;
        tx[k] = q.tx;
        ty[k] = q.ty;
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        ETK_PREFETCH(texels + 3 * (r0[k] * env.tex_w + c0[k]));
        ETK_PREFETCH(texels + 3 * (r1[k] * env.tex_w + c0[k]));
    }
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        EtkTexelQuad q;
        q.r0 = r0[k];
        q.r1 = r1[k];
        q.c0 = c0[k];
        q.c1 = c1[k];
        q.tx = tx[k];
        q.ty = ty[k];
        r[k] = etk_env_blend_channel(texels, env.tex_w, q, 0) * env.scale;
        g[k] = etk_env_blend_channel(texels, env.tex_w, q, 1) * env.scale;
        b[k] = etk_env_blend_channel(texels, env.tex_w, q, 2) * env.scale;
    }
}

// A batch of light samples as the sample_lights stage stores them (integrator.h): direction,
// density, radiance and cell of each, from the sample values (xu, xv). Also drawn by
// kernels/envmap_sample.cl, so a test can compare a device's batch with its one-by-one samples.
// Interleaved natively and on CPU devices (ETK_CPU_DEVICE), where the batch exists for their
// caches; one sample after another on other OpenCL devices: on an NVIDIA H200 (driver
// 580.159.04) the interleaved steps inside the wavefront program drew wrong samples -- images
// 10% dark, different from run to run -- though the same functions pass in a small kernel
// (EnvmapSampling tests) and the sample_lights stage drawing one by one gives the shade stage's
// own bits (docs/devices.md). A GPU hides the latency with other work-items anyway.
ETK_STRUCT_INLINE_FN void etk_env_light_batch(ETK_GLOBAL const float* dist,
                                              ETK_GLOBAL const float* texels, EtkEnvMap env,
                                              const float* xu, const float* xv, float* dx,
                                              float* dy, float* dz, float* pdf, float* Lr,
                                              float* Lg, float* Lb, int* row, int* col) {
#if defined(ETK_OPENCL_C) && !defined(ETK_CPU_DEVICE)
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        EtkEnvSample e = etk_env_sample(dist, env, make_float2(xu[k], xv[k]));
        float3 L = etk_env_radiance_uv(texels, env, e.uv);
        dx[k] = e.dir.x;
        dy[k] = e.dir.y;
        dz[k] = e.dir.z;
        pdf[k] = e.pdf;
        Lr[k] = L.x;
        Lg[k] = L.y;
        Lb[k] = L.z;
        row[k] = e.row;
        col[k] = e.col;
    }
#else
    // Arrays of scalars (etk_env_sample_batch_uv): the loops vectorise on PoCL too.
    float u[ETK_LIGHT_BATCH], v[ETK_LIGHT_BATCH], pdf_uv[ETK_LIGHT_BATCH];
    etk_env_sample_batch_uv(dist, env, xu, xv, u, v, pdf_uv, row, col);
    etk_env_sample_batch_dir(env, u, v, pdf_uv, dx, dy, dz, pdf);
    etk_env_radiance_batch(texels, env, u, v, Lr, Lg, Lb);
#endif
}

ETK_END

#endif
