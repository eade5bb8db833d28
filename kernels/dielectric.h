// Dielectric interfaces (glass, water): a smooth one (a delta lobe of each, reflection and
// refraction, chosen by the Fresnel reflectance) and a rough one (GGX microfacets, Walter et al.
// 2007, "Microfacet Models for Refraction through Rough Surfaces"), both without absorption.
//
// Local frame as in bsdf.h, with one convention more: the frame is always turned to the side of
// wo (wo.z > 0; the surface set-up flips the normal to the viewer), and eta is the relative
// index of refraction across the interface seen from there, eta = n(far side) / n(wo's side):
// ior when the ray arrives from outside (the triangle's front face), 1 / ior from inside
// (surface.h sets it). Reflected directions have wi.z > 0, transmitted ones wi.z < 0.
//
// Radiance, not importance: envtrace traces paths from the camera and gathers radiance, and
// radiance crossing into a denser medium is compressed into a narrower cone (L / n^2 is
// invariant), so the BTDF of a camera path carries the non-symmetric factor 1 / eta^2 (Veach
// 1997, 5.2; pbrt's TransportMode::Radiance). A path that enters and leaves a closed object
// gets eta^-2 and eta^2: nothing on balance. The transmission is multiplied by `tint` at each
// crossing (a thin-shell colour, the MTL's Tf), white by default; reflection is never tinted.
//
// Rough lobe: f_r = F D G / (4 |wo.z| |wi.z|) with h = normalize(wo + wi), and
// f_t = (1 - F) D G |wi.h| |wo.h| / (|wi.z| wo.z (wi.h + wo.h / eta)^2) / eta^2 with the
// generalised half vector h = normalize(wo + eta wi) turned to +z (Walter's eqs. 16 and 21),
// zero where h faces away from wo or towards wi. G is the separable Smith term of bsdf.h. A
// sample draws h (from visible normals, or from D(h) cos(theta_h), as the opaque GGX lobe),
// then reflects with probability F(wo.h) and refracts otherwise: the pdf is the half vector's
// density times F or 1 - F over the Jacobian 4 |wo.h| (reflection) or
// (wi.h + wo.h / eta)^2 / |wi.h| (refraction). So the pdf is positive wherever f is (F < 1
// where refraction is possible, F > 0 for eta != 1), over the whole sphere: light samples may
// come from either side, and the MIS-compensated distribution stays unbiased (the BSDF reaches
// every direction it contributes from). At eta = 1 every microfacet passes the ray straight on:
// the lobe is a delta (wi = -wo), handled as the smooth interface (pbrt-v4 does the same).
#ifndef ETK_DIELECTRIC_H
#define ETK_DIELECTRIC_H
#include "compat.h"
#include "ggx.h"

ETK_BEGIN

// Fresnel reflectance of unpolarised light at a dielectric interface, cos_i = cosine of the
// incident angle on the incident side (>= 0), eta = n_t / n_i. 1 under total internal reflection.
ETK_FN float etk_fresnel_dielectric(float cos_i, float eta) {
    cos_i = clamp(cos_i, 0.0f, 1.0f);
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f)
        return 1.0f;
    float cos_t = sqrt(fmax(0.0f, 1.0f - sin2_t));
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

// wo refracted through the interface of normal n (wo.n > 0), eta = n_t / n_i; the caller has
// excluded total internal reflection.
ETK_FN float3 etk_refract(float3 wo, float3 n, float eta) {
    float c = dot(wo, n);
    float sin2_t = fmax(0.0f, 1.0f - c * c) / (eta * eta);
    float cos_t = sqrt(fmax(0.0f, 1.0f - sin2_t));
    return normalize(n * (c / eta - cos_t) - wo / eta);
}

// Whether the interface is a delta lobe: smooth, or (rough with) no change of index.
ETK_FN int etk_dielectric_is_delta(int smooth, float eta) {
    return smooth || eta == 1.0f;
}

// The rough transmission's half vector normalize(wo + eta wi) turned to +z, and its validity:
// h must face wo and face away from wi. *ok = 0 where no microfacet refracts wo into wi.
ETK_FN float3 etk_dielectric_half_t(float3 wo, float3 wi, float eta, int* ok) {
    float3 h = wo + wi * eta;
    float l = length(h);
    *ok = l > 0.0f && wo.z > 0.0f && wi.z < 0.0f;
    if (!*ok)
        return make_float3(0.0f, 0.0f, 1.0f);
    h = h / l;
    if (h.z < 0.0f)
        h = -h;
    *ok = dot(wo, h) > 0.0f && dot(wi, h) < 0.0f;
    return h;
}

// Density of the drawn half vector h (h.z > 0, wo.h > 0).
ETK_FN float etk_dielectric_half_pdf(float3 wo, float3 h, float alpha, int vndf) {
    float d = etk_ggx_d(h.z, alpha);
    return vndf ? etk_smith_g1(wo.z, alpha) * dot(wo, h) * d / wo.z : d * h.z;
}

// f(wo, wi) of the rough interface (no cosine), tint on the transmission.
ETK_FN float3 etk_dielectric_eval(float3 tint, float eta, float alpha, float3 wo, float3 wi) {
    float3 zero = make_float3(0.0f, 0.0f, 0.0f);
    if (wo.z <= 0.0f || wi.z == 0.0f || eta == 1.0f)
        return zero;
    float g = etk_smith_g1(wo.z, alpha) * etk_smith_g1(wi.z, alpha);
    if (wi.z > 0.0f) {
        float3 h = normalize(wo + wi);
        float f = etk_fresnel_dielectric(dot(wo, h), eta);
        float r = f * etk_ggx_d(h.z, alpha) * g / (4.0f * wo.z * wi.z);
        return make_float3(r, r, r);
    }
    int ok;
    float3 h = etk_dielectric_half_t(wo, wi, eta, &ok);
    if (!ok)
        return zero;
    float oh = dot(wo, h), ih = dot(wi, h);
    float f = etk_fresnel_dielectric(oh, eta);
    float s = ih + oh / eta;
    float t = (1.0f - f) * etk_ggx_d(h.z, alpha) * g * fabs(ih * oh) /
              (s * s * fabs(wi.z) * wo.z * eta * eta);
    return tint * t;
}

ETK_FN float etk_dielectric_pdf(float eta, float alpha, int vndf, float3 wo, float3 wi) {
    if (wo.z <= 0.0f || wi.z == 0.0f || eta == 1.0f)
        return 0.0f;
    if (wi.z > 0.0f) {
        float3 h = normalize(wo + wi);
        float oh = dot(wo, h);
        return etk_dielectric_half_pdf(wo, h, alpha, vndf) * etk_fresnel_dielectric(oh, eta) /
               (4.0f * oh);
    }
    int ok;
    float3 h = etk_dielectric_half_t(wo, wi, eta, &ok);
    if (!ok)
        return 0.0f;
    float oh = dot(wo, h), ih = dot(wi, h);
    float s = ih + oh / eta;
    return etk_dielectric_half_pdf(wo, h, alpha, vndf) * (1.0f - etk_fresnel_dielectric(oh, eta)) *
           fabs(ih) / (s * s);
}

// One sample of the interface: direction, f |cos| / pdf, pdf (for the delta lobe, the
// probability of the branch taken), whether it is a delta. u: the direction; lobe: reflection
// (lobe < F) or refraction. pdf 0: no sample.
ETK_FN void etk_dielectric_sample(float3 tint, float eta, float alpha, int vndf, int smooth,
                                  float3 wo, float2 u, float lobe, float3* wi, float3* weight,
                                  float* pdf, int* delta) {
    *pdf = 0.0f;
    *delta = 0;
    *weight = make_float3(0.0f, 0.0f, 0.0f);
    *wi = make_float3(0.0f, 0.0f, 1.0f);
    if (wo.z <= 0.0f)
        return;
    if (etk_dielectric_is_delta(smooth, eta)) {
        float f = eta == 1.0f ? 0.0f : etk_fresnel_dielectric(wo.z, eta);
        *delta = 1;
        if (lobe < f) {
            *wi = make_float3(-wo.x, -wo.y, wo.z);
            *weight = make_float3(1.0f, 1.0f, 1.0f);
            *pdf = f;
        } else {
            *wi = eta == 1.0f ? -wo : etk_refract(wo, make_float3(0.0f, 0.0f, 1.0f), eta);
            *weight = tint / (eta * eta);
            *pdf = 1.0f - f;
        }
        return;
    }
    float3 h = vndf ? etk_sample_ggx_vndf(wo, alpha, u) : etk_sample_ggx_ndf(alpha, u);
    float oh = dot(wo, h);
    if (oh <= 0.0f)
        return;
    float f = etk_fresnel_dielectric(oh, eta);
    float3 w = lobe < f ? h * (2.0f * oh) - wo : etk_refract(wo, h, eta);
    if (lobe < f ? w.z <= 0.0f : w.z >= 0.0f)
        return; // reflected below, or refracted above, the macro-surface: lost
    float p = etk_dielectric_pdf(eta, alpha, vndf, wo, w);
    if (!(p > 0.0f))
        return;
    *wi = w;
    *pdf = p;
    *weight = etk_dielectric_eval(tint, eta, alpha, wo, w) * (fabs(w.z) / p);
}

ETK_END

#endif
