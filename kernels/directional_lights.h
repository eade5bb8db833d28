// Direct lighting from a finite set of directional lights, and from SIS strata (Agarwal et al.
// 2003): the per-light evaluation shared by the host loop (host/lib/light_render.cpp) and any
// kernel that includes it. Kept apart from integrator.h on purpose: the wavefront stages trace
// one shadow ray per path, these estimators trace one per light.
//
// A directional light k carries E_k = the integral of L over the directions it stands for (the
// map's power in its share, W m^-2): it adds f(wo, wi_k) E_k cos(theta_k) V(wi_k) to a point.
// The camera ray and the shading frame are those of etk_generate and etk_shade (integrator.h),
// repeated here so that these renders and the path tracer's agree pixel for pixel.
#ifndef ETK_DIRECTIONAL_LIGHTS_H
#define ETK_DIRECTIONAL_LIGHTS_H
#include "bsdf.h"
#include "bvh.h"
#include "compat.h"
#include "envmap.h"
#include "integrator.h"
#include "sampler.h"

ETK_BEGIN

// The camera ray of sample `sample_index` of `pixel` (pixel jitter from pair 0, as etk_generate).
ETK_FN float3 etk_dl_camera_dir(EtkParams p, int pixel) {
    float2 j = etk_dims(p, pixel, 0u);
    float px = (float)(pixel % p.width) + j.x, py = (float)(pixel / p.width) + j.y;
    float sx = 2.0f * px / (float)p.width - 1.0f, sy = 1.0f - 2.0f * py / (float)p.height;
    return normalize(etk_p3(p.forward) + etk_p3(p.right) * sx + etk_p3(p.up) * sy);
}

// What a surface point needs to be lit by any direction: its shading frame, the outgoing
// direction in that frame, the geometric normal facing the viewer, the material and the origin
// of its shadow rays.
typedef struct {
    float3 t, b, ns, ng, origin, wo;
    EtkMaterial m;
} EtkSurface;

// Mirrors the set-up of etk_shade for the closest hit `h` of the ray (o, d).
ETK_FN EtkSurface etk_dl_surface(EtkScene S, EtkParams p, float3 o, float3 d, EtkHit h) {
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

// f(wo, wi) E cos(theta_i) for a light of power E from world direction wi_world, before the
// shadow ray; zero below the shading or the geometric surface and for delta materials.
ETK_FN float3 etk_dl_unshadowed(EtkSurface s, float3 wi_world, float3 E) {
    float3 zero = make_float3(0.0f, 0.0f, 0.0f);
    if (etk_bsdf_is_delta(s.m) || dot(wi_world, s.ng) <= 0.0f)
        return zero;
    float3 wi = etk_to_local(wi_world, s.t, s.b, s.ns);
    if (wi.z <= 0.0f)
        return zero;
    return etk_bsdf_eval(s.m, s.wo, wi) * E * wi.z;
}

// The full contribution of one light: unshadowed term times visibility (one any-hit ray).
ETK_FN float3 etk_dl_light(EtkScene S, EtkSurface s, float3 wi_world, float3 E) {
    float3 c = etk_dl_unshadowed(s, wi_world, E);
    if (!(etk_max3(c) > 0.0f))
        return make_float3(0.0f, 0.0f, 0.0f);
    EtkHit h;
    if (etk_bvh_traverse(S.nodes, S.tris, s.origin, wi_world, 3.0e38f, 1, &h))
        return make_float3(0.0f, 0.0f, 0.0f);
    return c;
}

// A direction uniformly distributed (in solid angle) over the texels of one stratum of a
// lat-long grid of w x h texels. The stratum's texels are texels[first .. last) (row * w + col),
// cdf[k] the fraction of the stratum's solid angle in texels[first .. k] (cdf[last - 1] = 1).
// u.x picks the texel and, rescaled, the longitude inside it; u.y the cosine of the colatitude.
// Returns the map-space direction.
ETK_FN float3 etk_dl_stratum_direction(ETK_GLOBAL const int* texels, ETK_GLOBAL const float* cdf,
                                       int first, int last, int w, int h, float2 u) {
    int lo = first, hi = last - 1;
    while (lo < hi) { // first k with cdf[k] > u.x
        int mid = (lo + hi) / 2;
        if (cdf[mid] > u.x)
            hi = mid;
        else
            lo = mid + 1;
    }
    float c0 = lo > first ? cdf[lo - 1] : 0.0f, c1 = cdf[lo];
    float fx = c1 > c0 ? clamp((u.x - c0) / (c1 - c0), 0.0f, ETK_ONE_MINUS_EPS) : 0.5f;
    int texel = texels[lo];
    int row = texel / w, col = texel % w;
    float z0 = cos(ETK_PI * (float)row / (float)h), z1 = cos(ETK_PI * (float)(row + 1) / (float)h);
    float y = z0 + (z1 - z0) * u.y; // y = cos(theta): uniform in solid angle within the row
    float st = sqrt(fmax(0.0f, 1.0f - y * y));
    float phi = ETK_PI * (2.0f * ((float)col + fx) / (float)w - 1.0f);
    return make_float3(st * sin(phi), y, -st * cos(phi));
}

ETK_END

#endif
