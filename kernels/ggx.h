// The GGX (Trowbridge-Reitz) microfacet distribution shared by the opaque microfacet lobe
// (bsdf.h) and the rough dielectric (dielectric.h): D, the separable Smith masking term, and the
// two ways of drawing a normal (from D(h) cos(theta_h), and from the normals visible from wo).
// Local frame: the macro-surface normal is +z.
#ifndef ETK_GGX_H
#define ETK_GGX_H
#include "compat.h"
#include "trig.h"

ETK_BEGIN

// How a GGX lobe is sampled (EtkMaterial.ggx_sampling, bsdf.h): from D(h) cos(theta_h), from the
// normals visible from wo, or from the even mixture of the two (one-sample MIS: the density is
// the mean of both, so f cos / pdf is never above twice the better technique's -- neither the
// NDF's weights that explode at grazing wo nor the visible normals' sparser samples of
// microfacets turned away from wo; docs/history/results-journal.md).
#define ETK_GGX_NDF 0
#define ETK_GGX_VNDF 1
#define ETK_GGX_MIX 2

// The nodes of the lobe's directional albedo table (base_albedo_table.h): square roots of the
// cosine and of alpha, evenly spaced.
#define ETK_BASE_TABLE_MU 64
#define ETK_BASE_TABLE_ALPHA 32

ETK_FN float etk_ggx_d(float cos_h, float alpha) {
    float a2 = alpha * alpha;
    float c2 = cos_h * cos_h;
    float d = c2 * (a2 - 1.0f) + 1.0f;
    return a2 / (ETK_PI * d * d);
}
ETK_FN float etk_smith_g1(float cos_v, float alpha) {
    float c2 = cos_v * cos_v;
    float tan2 = fmax(0.0f, 1.0f - c2) / fmax(c2, 1e-12f);
    return 2.0f / (1.0f + sqrt(1.0f + alpha * alpha * tan2));
}
// A GGX normal visible from wo (wo.z > 0), with density G1(wo) max(0, wo.h) D(h) / wo.z:
// stretch wo to the unit-roughness configuration, sample the projected hemisphere seen from it
// (a disk, its far half squeezed by the hemisphere's tilt), unstretch (Heitz 2018, listing 1).
ETK_FN float3 etk_sample_ggx_vndf(float3 wo, float alpha, float2 u) {
    float3 vh = normalize(make_float3(alpha * wo.x, alpha * wo.y, wo.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    float inv = lensq > 0.0f ? 1.0f / sqrt(lensq) : 0.0f;
    float3 t1 =
        lensq > 0.0f ? make_float3(-vh.y * inv, vh.x * inv, 0.0f) : make_float3(1.0f, 0.0f, 0.0f);
    float3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float2 sc = etk_sincospi(2.0f * u.y);
    float p1 = r * sc.y, p2 = r * sc.x;
    float sh = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - sh) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + sh * p2;
    float3 nh = t1 * p1 + t2 * p2 + vh * sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2));
    return normalize(make_float3(alpha * nh.x, alpha * nh.y, fmax(1e-7f, nh.z)));
}

// A GGX normal drawn from D(h) cos(theta_h) (the paper's sampling; Walter et al. 2007, eq. 35).
ETK_FN float3 etk_sample_ggx_ndf(float alpha, float2 u) {
    float a2 = alpha * alpha;
    float cos2 = (1.0f - u.x) / (1.0f + (a2 - 1.0f) * u.x);
    float ct = sqrt(fmax(0.0f, cos2)), st = sqrt(fmax(0.0f, 1.0f - cos2));
    float2 sc = etk_sincospi(2.0f * u.y);
    return make_float3(st * sc.y, st * sc.x, ct);
}

ETK_END

#endif
