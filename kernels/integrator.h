// The wavefront path tracer's stages, written once for the OpenCL kernels (wavefront.cl) and the
// native back end. Paths live in structure-of-arrays buffers indexed by slot; work queues are
// arrays of slots whose lengths are counters bumped atomically, so every stage runs over exactly
// the live work. One path per pixel per pass: film accumulation needs no atomics.
//
// Sample dimensions (pairs, regenerated from pixel, sample index, pair; never stored):
//   pair 0: pixel jitter; for bounce d: pair 1+3d light sample, 2+3d BSDF direction,
//   3+3d (BSDF lobe, Russian roulette).
#ifndef ETK_INTEGRATOR_H
#define ETK_INTEGRATOR_H
#include "bsdf.h"
#include "bvh.h"
#include "compat.h"
#include "envmap.h"
#include "sampler.h"

#define ETK_STRATEGY_LIGHT 0
#define ETK_STRATEGY_BSDF 1
#define ETK_STRATEGY_MIS 2
#define ETK_STRATEGY_UNIFORM 3
#define ETK_HEURISTIC_BALANCE 0
#define ETK_HEURISTIC_POWER 1

// Queue counters.
#define ETK_Q_RAY_OUT 0
#define ETK_Q_ESCAPED 1
#define ETK_Q_SHADE 2
#define ETK_Q_SHADOW 3
#define ETK_Q_NONFINITE 4 // samples dropped by etk_accumulate: should stay 0
#define ETK_Q_COUNT 5

ETK_BEGIN

// Per-pass parameters; 4-byte members only (passed by value to kernels).
typedef struct {
    EtkEnvMap env;
    float eye[3], forward[3], right[3], up[3]; // right/up scaled by the field of view
    int width, height;
    int max_depth, rr_depth;
    int strategy, heuristic;
    int sampler;
    uint seed;
    uint sample_index; // the pass: which sample of each pixel
    int first_pixel;   // pixel of slot 0 in this pass
    float ray_epsilon; // offset of secondary ray origins, scaled to the scene
    int pad;
} EtkParams;

typedef struct {
    ETK_GLOBAL const float4* nodes;
    ETK_GLOBAL const float4* tris;    // v0, e1, e2 per triangle
    ETK_GLOBAL const float4* normals; // three vertex normals per triangle
    ETK_GLOBAL const int* tri_material;
    ETK_GLOBAL const float4* materials;
    ETK_GLOBAL const float* env_dist;
    ETK_GLOBAL const float* env_texels;
} EtkScene;

typedef struct {
    ETK_GLOBAL float4* ray_o;    // origin; w: depth (number of surface interactions so far)
    ETK_GLOBAL float4* ray_d;    // direction; w: pdf of the BSDF sample that made it, < 0 if none
    ETK_GLOBAL float4* beta;     // throughput
    ETK_GLOBAL float4* radiance; // accumulated along the path
    ETK_GLOBAL float4* hit;      // t, triangle (int bits), b1, b2
    ETK_GLOBAL float4* shadow_o;
    ETK_GLOBAL float4* shadow_d;
    ETK_GLOBAL float4* shadow_L; // tentative contribution of the shadow ray
    ETK_GLOBAL int* pixel;
} EtkPaths;

typedef struct {
    ETK_GLOBAL const int* ray_in;
    ETK_GLOBAL int* ray_out;
    ETK_GLOBAL int* escaped;
    ETK_GLOBAL int* shade;
    ETK_GLOBAL int* shadow;
    ETK_ATOMIC_PTR counters;
} EtkQueues;

ETK_FN float3 etk_xyz(float4 v) {
    return make_float3(v.x, v.y, v.z);
}
ETK_FN float4 etk_f4(float3 v, float w) {
    return make_float4(v.x, v.y, v.z, w);
}
ETK_FN float3 etk_p3(const float* p) {
    return make_float3(p[0], p[1], p[2]);
}

ETK_FN float etk_mis_weight(int heuristic, float a, float b) {
    if (heuristic == ETK_HEURISTIC_POWER) {
        a *= a;
        b *= b;
    }
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

ETK_FN float2 etk_dims(EtkParams p, int pixel, uint pair) {
    return etk_sample_pair(p.sampler, p.seed, (uint)pixel, p.sample_index, pair);
}

// The camera ray direction of sample p.sample_index of `pixel` (pixel jitter from pair 0).
ETK_FN float3 etk_camera_dir(EtkParams p, int pixel) {
    float2 j = etk_dims(p, pixel, 0u);
    float px = (float)(pixel % p.width) + j.x, py = (float)(pixel / p.width) + j.y;
    float sx = 2.0f * px / (float)p.width - 1.0f, sy = 1.0f - 2.0f * py / (float)p.height;
    return normalize(etk_p3(p.forward) + etk_p3(p.right) * sx + etk_p3(p.up) * sy);
}

// What a surface point needs to be lit from any direction: its shading frame (t, b, ns), the
// geometric normal facing the viewer, the outgoing direction in the frame, the material and
// the origin of rays leaving it.
typedef struct {
    float3 t, b, ns, ng, origin, wo;
    EtkMaterial m;
} EtkSurface;

// The surface at the closest hit h of the ray (o, d). Surfaces are two-sided; the shading
// normal is flipped to the geometric normal's side.
ETK_FN EtkSurface etk_surface_at(EtkScene S, EtkParams p, float3 o, float3 d, EtkHit h) {
    EtkSurface s;
    int prim = h.prim;
    float3 pos = o + d * h.t;
    float4 e1 = S.tris[3 * prim + 1], e2 = S.tris[3 * prim + 2];
    float3 ng = normalize(cross(etk_xyz(e1), etk_xyz(e2)));
    float b0 = 1.0f - h.b1 - h.b2;
    float3 ns = etk_xyz(S.normals[3 * prim]) * b0 + etk_xyz(S.normals[3 * prim + 1]) * h.b1 +
                etk_xyz(S.normals[3 * prim + 2]) * h.b2;
    float nl = length(ns);
    ns = nl > 0.0f && isfinite(nl) ? ns / nl : ng;
    float3 wo_world = -d;
    if (dot(ng, wo_world) < 0.0f)
        ng = -ng;
    if (dot(ns, ng) < 0.0f)
        ns = -ns;
    etk_make_frame(ns, &s.t, &s.b);
    s.ns = ns;
    s.ng = ng;
    s.wo = etk_to_local(wo_world, s.t, s.b, ns);
    s.m = etk_material_load(S.materials, S.tri_material[prim]);
    float scale = fmax(fmax(fabs(pos.x), fabs(pos.y)), fmax(fabs(pos.z), 1.0f));
    s.origin = pos + ng * (p.ray_epsilon * scale);
    return s;
}

// Stage 1: a camera ray for slot i.
ETK_FN void etk_generate(EtkPaths P, EtkQueues Q, EtkParams p, int i) {
    int pixel = p.first_pixel + i;
    float3 d = etk_camera_dir(p, pixel);
    P.ray_o[i] = etk_f4(etk_p3(p.eye), 0.0f);
    P.ray_d[i] = etk_f4(d, -1.0f);
    P.beta[i] = make_float4(1.0f, 1.0f, 1.0f, 0.0f);
    P.radiance[i] = make_float4(0.0f, 0.0f, 0.0f, 0.0f);
    P.pixel[i] = pixel;
    Q.ray_out[i] = i;
}

// Stage 2: closest hit; routes the path to the escaped or the shading queue.
ETK_FN void etk_intersect(EtkPaths P, EtkQueues Q, EtkScene S, EtkParams p, int q) {
    int slot = Q.ray_in[q];
    float4 o = P.ray_o[slot], d = P.ray_d[slot];
    EtkHit h;
    if (!etk_bvh_traverse(S.nodes, S.tris, etk_xyz(o), etk_xyz(d), 3.0e38f, 0, &h)) {
        Q.escaped[ETK_ATOMIC_INC(Q.counters + ETK_Q_ESCAPED)] = slot;
        return;
    }
    if ((int)o.w >= p.max_depth)
        return; // the path ends here: no more bounces allowed
    P.hit[slot] = make_float4(h.t, as_float((uint)h.prim), h.b1, h.b2);
    Q.shade[ETK_ATOMIC_INC(Q.counters + ETK_Q_SHADE)] = slot;
}

// Stage 3: rays that left the scene see the environment, weighted against light sampling.
ETK_FN void etk_escaped(EtkPaths P, EtkQueues Q, EtkScene S, EtkParams p, int q) {
    int slot = Q.escaped[q];
    float4 d = P.ray_d[slot];
    float2 uv = etk_env_uv(p.env, etk_xyz(d));
    float w = 1.0f;
    if (d.w >= 0.0f) { // made by a non-delta BSDF sample
        if (p.strategy == ETK_STRATEGY_MIS)
            w = etk_mis_weight(p.heuristic, d.w, etk_env_pdf_uv(S.env_dist, p.env, uv));
        else if (p.strategy != ETK_STRATEGY_BSDF)
            w = 0.0f; // light sampling alone accounts for this direction
    }
    if (w > 0.0f) {
        float3 L = etk_env_radiance_uv(S.env_texels, p.env, uv) * w;
        float4 r = P.radiance[slot];
        P.radiance[slot] = etk_f4(etk_xyz(r) + etk_xyz(P.beta[slot]) * L, 0.0f);
    }
}

// Stage 4: at a surface: one light sample (pushed as a shadow ray) and one BSDF sample (pushed as
// the continuation ray).
ETK_FN void etk_shade(EtkPaths P, EtkQueues Q, EtkScene S, EtkParams p, int q) {
    int slot = Q.shade[q];
    float4 o4 = P.ray_o[slot], d4 = P.ray_d[slot], h4 = P.hit[slot];
    int depth = (int)o4.w;
    int pixel = P.pixel[slot];
    EtkHit h;
    h.t = h4.x;
    h.prim = (int)as_uint(h4.y);
    h.b1 = h4.z;
    h.b2 = h4.w;
    EtkSurface s = etk_surface_at(S, p, etk_xyz(o4), etk_xyz(d4), h);
    float3 t = s.t, b = s.b, ns = s.ns, ng = s.ng, wo = s.wo, origin = s.origin;
    EtkMaterial m = s.m;
    float3 beta = etk_xyz(P.beta[slot]);
    uint pair = 1u + 3u * (uint)depth;

    // Light sample.
    if (p.strategy != ETK_STRATEGY_BSDF && !etk_bsdf_is_delta(m)) {
        float2 u = etk_dims(p, pixel, pair);
        float3 wi_world;
        float2 light_uv; // map coordinates of the light direction
        float pdf_light;
        if (p.strategy == ETK_STRATEGY_UNIFORM) {
            wi_world = etk_sample_uniform_sphere(u);
            light_uv = etk_env_uv(p.env, wi_world);
            pdf_light = 0.25f * ETK_INV_PI;
        } else {
            EtkEnvSample ls = etk_env_sample(S.env_dist, p.env, u);
            wi_world = ls.dir;
            light_uv = ls.uv;
            pdf_light = ls.pdf;
        }
        float3 wi = etk_to_local(wi_world, t, b, ns);
        if (pdf_light > 0.0f && wi.z > 0.0f && dot(wi_world, ng) > 0.0f) {
            float3 f = etk_bsdf_eval(m, wo, wi);
            float w = p.strategy == ETK_STRATEGY_MIS
                          ? etk_mis_weight(p.heuristic, pdf_light, etk_bsdf_pdf(m, wo, wi))
                          : 1.0f;
            float3 L = etk_env_radiance_uv(S.env_texels, p.env, light_uv);
            float3 c = beta * f * L * (wi.z * w / pdf_light);
            if (etk_max3(c) > 0.0f) {
                int k = (int)ETK_ATOMIC_INC(Q.counters + ETK_Q_SHADOW);
                P.shadow_o[slot] = etk_f4(origin, 0.0f);
                P.shadow_d[slot] = etk_f4(wi_world, 3.0e38f);
                P.shadow_L[slot] = etk_f4(c, 0.0f);
                Q.shadow[k] = slot;
            }
        }
    }

    // BSDF sample: the continuation. Not needed when nothing it could reach would count.
    int last = depth + 1 >= p.max_depth;
    if (last && p.strategy != ETK_STRATEGY_BSDF && p.strategy != ETK_STRATEGY_MIS &&
        !etk_bsdf_is_delta(m))
        return;
    float2 rr = etk_dims(p, pixel, pair + 2u);
    EtkBsdfSample bs = etk_bsdf_sample(m, wo, etk_dims(p, pixel, pair + 1u), rr.x);
    if (!(bs.pdf > 0.0f))
        return;
    float3 wi_world = etk_from_local(bs.wi, t, b, ns);
    if (dot(wi_world, ng) <= 0.0f)
        return; // below the geometric surface: the shading normal would leak light
    beta = beta * bs.weight;
    if (depth + 1 >= p.rr_depth) {
        float survive = fmin(0.95f, etk_max3(beta));
        if (!(rr.y < survive))
            return;
        beta = beta / survive;
    }
    if (!(etk_max3(beta) > 0.0f) || !isfinite(etk_max3(beta)))
        return;
    P.ray_o[slot] = etk_f4(origin, (float)(depth + 1));
    P.ray_d[slot] = etk_f4(normalize(wi_world), bs.delta ? -1.0f : bs.pdf);
    P.beta[slot] = etk_f4(beta, 0.0f);
    Q.ray_out[ETK_ATOMIC_INC(Q.counters + ETK_Q_RAY_OUT)] = slot;
}

// Stage 5: shadow rays add their contribution when nothing blocks them.
ETK_FN void etk_shadow(EtkPaths P, EtkQueues Q, EtkScene S, int q) {
    int slot = Q.shadow[q];
    float4 o = P.shadow_o[slot], d = P.shadow_d[slot];
    EtkHit h;
    if (!etk_bvh_traverse(S.nodes, S.tris, etk_xyz(o), etk_xyz(d), d.w, 1, &h)) {
        float4 r = P.radiance[slot];
        P.radiance[slot] = etk_f4(etk_xyz(r) + etk_xyz(P.shadow_L[slot]), 0.0f);
    }
}

// Stage 6: the pass's path radiance into the film (sum over passes). A non-finite sample counts
// as zero rather than poisoning the pixel, and is counted: the host reports any, and the tests
// require none.
ETK_FN void etk_accumulate(EtkPaths P, EtkQueues Q, ETK_GLOBAL float4* film, int i) {
    int pixel = P.pixel[i];
    float3 L = etk_xyz(P.radiance[i]);
    if (!(isfinite(L.x) && isfinite(L.y) && isfinite(L.z))) {
        ETK_ATOMIC_INC(Q.counters + ETK_Q_NONFINITE);
        L = make_float3(0.0f, 0.0f, 0.0f);
    }
    film[pixel] = etk_f4(etk_xyz(film[pixel]) + L, film[pixel].w + 1.0f);
}

ETK_END

#endif
