// Arbitrary output variables (AOVs) of a sample's first surface hit, for denoisers and
// compositors: the albedo, the shading normal and the depth, written once per pass into the
// film (one path per pixel per pass: no atomics). Escaped camera rays write nothing, so a pixel's
// film holds zeros there and counts no hit. The host adds the pass exactly to its sums
// (host/lib/render/film_aovs.h), like the radiance, and averages over all samples (albedo,
// normal: alpha-free, misses count as zero) or over the samples that hit (depth).
#ifndef ETK_AOV_H
#define ETK_AOV_H
#include "bsdf.h"
#include "compat.h"
#include "params.h"
#include "path_state.h"
#include "surface.h"

ETK_BEGIN

// The material's albedo as denoisers take it (Intel OIDN: the directional albedo, approximated):
// the diffuse reflectance, plus the specular reflectance at normal incidence for glossy
// lobes (a conductor's: its Fresnel reflectance there), each channel clamped to [0, 1]; a mirror's
// is its specular colour.
ETK_FN float3 etk_aov_albedo(EtkMaterial m) {
    float3 a = m.type == ETK_MAT_MIRROR       ? m.specular
               : m.type == ETK_MAT_MICROFACET ? m.albedo + m.specular
               : m.type == ETK_MAT_CONDUCTOR  ? etk_fresnel_conductor(m.albedo, m.specular, 1.0f)
                                              : m.albedo;
    return make_float3(fmin(fmax(a.x, 0.0f), 1.0f), fmin(fmax(a.y, 0.0f), 1.0f),
                       fmin(fmax(a.z, 0.0f), 1.0f));
}

// Called where a camera ray's closest hit is shaded (depth 0): albedo (w: 1, a hit), the shading
// normal in world space, facing the camera, and the depth: the distance along the camera's
// viewing axis (camera-space z, as compositors' Z channels hold), t * (d . forward).
ETK_FN void etk_aov_first_hit(EtkFilm F, EtkParams p, int pixel, EtkSurface s, float3 d, float t) {
    F.film_albedo[pixel] = etk_f4(etk_aov_albedo(s.m), 1.0f);
    F.film_normal[pixel] = etk_f4(s.ns, t * dot(d, etk_p3(p.forward)));
}

ETK_END

#endif
