// Direct lighting from a finite set of directional lights, and from SIS strata (Agarwal et al.
// 2003): the per-light evaluation that the shade stages of integrator.h use (shade_lights sums
// every light of the set at a hit; shade_hits with ETK_STRATEGY_SIS draws one stratum).
//
// A directional light k carries E_k = the integral of L over the directions it stands for (the
// map's power in its share, W m^-2): it adds f(wo, wi_k) E_k cos(theta_k) V(wi_k) to a point.
// The camera ray and the surface set-up are the path tracer's own (surface.h), so these renders
// and the path tracer's agree pixel for pixel.
#ifndef ETK_DIRECTIONAL_LIGHTS_H
#define ETK_DIRECTIONAL_LIGHTS_H
#include "bsdf.h"
#include "bvh.h"
#include "compat.h"
#include "envmap.h"
#include "latlong.h"
#include "sampler.h"
#include "surface.h"
#include "trig.h"

ETK_BEGIN

// f(wo, wi) E cos(theta_i) for a light of power E from world direction wi_world, before the
// shadow ray; zero for delta materials and where the shading and geometric surfaces disagree on
// the side of wi (below both: only a rough dielectric transmits).
ETK_FN float3 etk_dl_unshadowed(EtkSurface s, float3 wi_world, float3 E) {
    float3 zero = make_float3(0.0f, 0.0f, 0.0f);
    float3 wi = etk_to_local(wi_world, s.t, s.b, s.ns);
    if (etk_bsdf_is_delta(s.m) || !etk_light_side_ok(s.m, wi.z, dot(wi_world, s.ng)))
        return zero;
    return etk_bsdf_eval(s.m, s.wo, wi) * E * fabs(wi.z);
}

// Whether nothing blocks the direction wi_world from the surface (one any-hit ray).
ETK_FN int etk_dl_visible(EtkScene S, EtkSurface s, float3 wi_world) {
    EtkHit h;
    return !etk_bvh_traverse(S.nodes, S.packets, etk_surface_origin(s, wi_world), wi_world,
                             ETK_RAY_UNBOUNDED, 1, &h);
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
    float z0 = etk_cospi((float)row / (float)h), z1 = etk_cospi((float)(row + 1) / (float)h);
    float y = z0 + (z1 - z0) * u.y; // y = cos(theta): uniform in solid angle within the row
    return etk_latlong_dir(((float)col + fx) / (float)w, y, sqrt(fmax(0.0f, 1.0f - y * y)));
}

ETK_END

#endif
