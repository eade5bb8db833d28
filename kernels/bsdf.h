// Materials: Lambertian, Cook-Torrance microfacet (GGX distribution, separable Smith shadowing,
// Schlick Fresnel) with an optional Lambertian base ("plastic"), a conductor (the same GGX lobe
// with a metal's exact Fresnel reflectance), and a perfect mirror.
// Everything is in the local shading frame: normal = +z. Evaluations exclude the cosine term.
//
// A material is two float4: (albedo rgb, type as int bits), (specular F0 rgb, GGX alpha).
// The paper's "roughness" is used directly as the GGX alpha.
//
// The GGX lobe is sampled either from the distribution of normals, pdf(h) = D(h) cos(theta_h)
// (the paper's), or from the distribution of normals visible from wo (Heitz 2018, "Sampling the
// GGX Distribution of Visible Normals"), pdf(h) = G1(wo) max(0, wo.h) D(h) / wo.z: it never
// draws a normal that faces away from wo, so fewer samples go below the horizon and the weights
// f cos / pdf vary only through G1(wi) and the Fresnel term. EtkMaterial.ggx_sampling picks
// which (ETK_GGX_*); the pdf follows it.
//
// A conductor (ETK_MAT_CONDUCTOR) is the same GGX lobe with the exact Fresnel reflectance of a
// metal of complex index eta + i k per channel in place of Schlick's, and no diffuse base: it
// stores (eta rgb, type), (k rgb, GGX alpha), eta where the others keep the albedo, k where they
// keep F0.
//
// Dielectrics (glass; dielectric.h): ETK_MAT_DIELECTRIC (rough, GGX) and
// ETK_MAT_SMOOTH_DIELECTRIC (delta) store (tint rgb, type), (ior, -, -, GGX alpha); they transmit
// (wi.z < 0) and take the relative index eta of the side they are hit from (surface.h).
#ifndef ETK_BSDF_H
#define ETK_BSDF_H
#include "color.h"
#include "base_albedo_table.h"
#include "compat.h"
#include "dielectric.h"
#include "ggx.h"
#include "trig.h"

#define ETK_MAT_DIFFUSE 0
#define ETK_MAT_MICROFACET 1
#define ETK_MAT_MIRROR 2
#define ETK_MAT_DIELECTRIC 3        // rough glass (dielectric.h)
#define ETK_MAT_SMOOTH_DIELECTRIC 4 // smooth glass: delta reflection and refraction
#define ETK_MAT_CONDUCTOR 5         // metal: the GGX lobe with a conductor's Fresnel reflectance

ETK_BEGIN

typedef struct {
    float3 albedo;
    float3 specular;
    float alpha;
    int type;
    int ggx_sampling; // ETK_GGX_NDF or ETK_GGX_VNDF (ggx.h)
    float eta;        // dielectrics: n(far side) / n(side of wo) (dielectric.h); set by surface.h
} EtkMaterial;

ETK_FN EtkMaterial etk_material_load(ETK_GLOBAL const float4* mats, int id) {
    float4 a = mats[2 * id], b = mats[2 * id + 1];
    EtkMaterial m;
    m.albedo = make_float3(a.x, a.y, a.z);
    m.type = (int)a.w; // a float value, not int bits: a.w rides along in albedo's fourth lane
    m.specular = make_float3(b.x, b.y, b.z);
    m.alpha = fmax(b.w, 1e-3f);
    m.ggx_sampling = ETK_GGX_NDF;
    m.eta = b.x; // dielectrics: the ior, as seen from outside
    return m;
}

ETK_FN float etk_max3(float3 v) {
    return fmax(v.x, fmax(v.y, v.z));
}

// Orthonormal basis around n (Duff et al. 2017).
ETK_FN void etk_make_frame(float3 n, float3* t, float3* b) {
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z);
    float c = n.x * n.y * a;
    *t = make_float3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = make_float3(c, s + n.y * n.y * a, -n.y);
}
ETK_FN float3 etk_to_local(float3 v, float3 t, float3 b, float3 n) {
    return make_float3(dot(v, t), dot(v, b), dot(v, n));
}
ETK_FN float3 etk_from_local(float3 v, float3 t, float3 b, float3 n) {
    return t * v.x + b * v.y + n * v.z;
}

// Cosine-weighted hemisphere by the concentric disk map (Shirley & Chiu 1997).
ETK_FN float3 etk_sample_cosine_hemisphere(float2 u) {
    float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
    float r = 0.0f, phi = 0.0f; // phi in units of pi
    if (ox != 0.0f || oy != 0.0f) {
        if (fabs(ox) > fabs(oy)) {
            r = ox;
            phi = 0.25f * (oy / ox);
        } else {
            r = oy;
            phi = 0.5f - 0.25f * (ox / oy);
        }
    }
    float2 sc = etk_sincospi(phi);
    float x = r * sc.y, y = r * sc.x;
    return make_float3(x, y, sqrt(fmax(0.0f, 1.0f - x * x - y * y)));
}

ETK_FN float3 etk_sample_uniform_sphere(float2 u) {
    float z = 1.0f - 2.0f * u.x;
    float r = sqrt(fmax(0.0f, 1.0f - z * z));
    float2 sc = etk_sincospi(2.0f * u.y);
    return make_float3(r * sc.y, r * sc.x, z);
}

ETK_FN float3 etk_schlick(float3 f0, float cos_d) {
    float m = clamp(1.0f - cos_d, 0.0f, 1.0f);
    float m5 = m * m * m * m * m;
    return f0 + (make_float3(1.0f, 1.0f, 1.0f) - f0) * m5;
}

// The unpolarised Fresnel reflectance of a conductor of complex index eta + i k (relative to the
// outside) at incidence cos_i, one channel (the exact form, as pbrt-v3's FrConductor and Mitsuba's
// fresnel_conductor write it; k = 0 gives a dielectric's reflectance from the outside).
ETK_FN float etk_fresnel_conductor1(float eta, float k, float cos_i) {
    float c2 = clamp(cos_i * cos_i, 0.0f, 1.0f), s2 = 1.0f - c2;
    float t0 = eta * eta - k * k - s2;
    float ab2 = sqrt(fmax(t0 * t0 + 4.0f * eta * eta * k * k, 0.0f)); // a^2 + b^2
    float a = sqrt(fmax(0.5f * (ab2 + t0), 0.0f));
    float t1 = ab2 + c2, t2 = 2.0f * a * sqrt(c2);
    // Clamped: where eta ~ 1 and k ~ 0 the differences t1 - t2 and t3 - t4 are rounding only and
    // can come out below zero (a negative reflectance makes negative pixels).
    float rs = clamp((t1 - t2) / fmax(t1 + t2, 1e-30f), 0.0f, 1.0f);
    float t3 = c2 * ab2 + s2 * s2, t4 = t2 * s2;
    float rp = rs * clamp((t3 - t4) / fmax(t3 + t4, 1e-30f), 0.0f, 1.0f);
    return 0.5f * (rs + rp);
}
ETK_FN float3 etk_fresnel_conductor(float3 eta, float3 k, float cos_i) {
    return make_float3(etk_fresnel_conductor1(eta.x, k.x, cos_i),
                       etk_fresnel_conductor1(eta.y, k.y, cos_i),
                       etk_fresnel_conductor1(eta.z, k.z, cos_i));
}

// Whether the material's lobe is the GGX reflection (Cook-Torrance or conductor).
ETK_FN int etk_bsdf_is_glossy(EtkMaterial m) {
    return m.type == ETK_MAT_MICROFACET || m.type == ETK_MAT_CONDUCTOR;
}

// The GGX lobe's Fresnel factor at cos_d = wi . h.
ETK_FN float3 etk_microfacet_fresnel(EtkMaterial m, float cos_d) {
    return m.type == ETK_MAT_CONDUCTOR ? etk_fresnel_conductor(m.albedo, m.specular, cos_d)
                                       : etk_schlick(m.specular, cos_d);
}

// The share of the Lambertian base under the GGX lobe: what the lobe's F0 leaves; none under a
// conductor (whose albedo slot holds eta).
ETK_FN float etk_base_share(EtkMaterial m) {
    return m.type == ETK_MAT_CONDUCTOR ? 0.0f : 1.0f - etk_max3(m.specular);
}

// A row of the lobe's albedo table (base_albedo_table.h): alpha's node j and the fraction fy
// towards the next, found once per evaluation and shared by its three lookups.
typedef struct {
    int j;
    float fy;
} EtkLobeRow;

ETK_FN EtkLobeRow etk_lobe_row(float alpha) {
    float y = sqrt(clamp(alpha, 0.0f, 1.0f)) * (float)(ETK_BASE_TABLE_ALPHA - 1);
    EtkLobeRow r;
    r.j = (int)y;
    r.j = r.j > ETK_BASE_TABLE_ALPHA - 2 ? ETK_BASE_TABLE_ALPHA - 2 : r.j;
    r.fy = y - (float)r.j;
    return r;
}

// The GGX lobe's directional albedo with Schlick's Fresnel of reflectance f0 (at least F0 of
// every channel), from the tabulated E = f0 A + B (bilinear in the square roots of the cosine
// and of alpha).
ETK_FN float etk_lobe_albedo(float cos_o, EtkLobeRow r, float f0) {
    float x = sqrt(clamp(cos_o, 0.0f, 1.0f)) * (float)(ETK_BASE_TABLE_MU - 1);
    int i = (int)x;
    i = i > ETK_BASE_TABLE_MU - 2 ? ETK_BASE_TABLE_MU - 2 : i;
    float fx = x - (float)i, fy = r.fy;
    int k = r.j * ETK_BASE_TABLE_MU + i;
    float a0 = etk_base_table_a[k] + (etk_base_table_a[k + 1] - etk_base_table_a[k]) * fx;
    float b0 = etk_base_table_b[k] + (etk_base_table_b[k + 1] - etk_base_table_b[k]) * fx;
    k += ETK_BASE_TABLE_MU;
    float a1 = etk_base_table_a[k] + (etk_base_table_a[k + 1] - etk_base_table_a[k]) * fx;
    float b1 = etk_base_table_b[k] + (etk_base_table_b[k + 1] - etk_base_table_b[k]) * fx;
    return f0 * (a0 + (a1 - a0) * fy) + (b0 + (b1 - b0) * fy);
}

// Its cosine-weighted mean over the hemisphere, 2 int E(mu) mu dmu.
ETK_FN float etk_lobe_mean_albedo(EtkLobeRow r, float f0) {
    int j = r.j;
    float a =
        etk_base_table_avg_a[j] + (etk_base_table_avg_a[j + 1] - etk_base_table_avg_a[j]) * r.fy;
    float b =
        etk_base_table_avg_b[j] + (etk_base_table_avg_b[j + 1] - etk_base_table_avg_b[j]) * r.fy;
    return f0 * a + b;
}

// The Lambertian base under the lobe receives what the lobe does not reflect, going in and
// coming out (Kelemen and Szirmay-Kalos 2001): (1 - E(cos_i)) (1 - E(cos_o)) / (1 - Eavg), so
// that its directional albedo is albedo (1 - E(cos_o)) and base plus lobe reflect exactly what
// a white base receives, at every angle and roughness (a constant 1 - F0 reflected 1.61 at 85
// degrees, smooth, F0 0.04, albedo 1; Fresnel's 1 - F in place of 1 - E lost half at grazing
// angles under rough lobes, whose shadowing reflects less than F). Reciprocal. The lobe's
// Fresnel is taken at the largest F0 of the three channels: no channel gains energy.
ETK_FN float etk_base_coupling(EtkMaterial m, float cos_i, float cos_o) {
    float f0 = etk_max3(m.specular);
    EtkLobeRow row = etk_lobe_row(m.alpha);
    float rest = 1.0f - etk_lobe_mean_albedo(row, f0);
    if (!(rest > 1e-4f))
        return 0.0f; // the lobe reflects (nearly) everything: no base
    float ei = etk_lobe_albedo(cos_i, row, f0), eo = etk_lobe_albedo(cos_o, row, f0);
    return fmax(0.0f, 1.0f - ei) * fmax(0.0f, 1.0f - eo) / rest;
}

// Probability of choosing the specular lobe of a microfacet material with a diffuse base.
ETK_FN float etk_specular_weight(EtkMaterial m) {
    float ws = etk_luma(m.specular);
    float wd = etk_luma(m.albedo) * etk_base_share(m);
    return ws + wd > 0.0f ? ws / (ws + wd) : 1.0f;
}

ETK_FN int etk_bsdf_is_dielectric(EtkMaterial m) {
    return m.type == ETK_MAT_DIELECTRIC || m.type == ETK_MAT_SMOOTH_DIELECTRIC;
}

ETK_FN int etk_bsdf_is_delta(EtkMaterial m) {
    return m.type == ETK_MAT_MIRROR ||
           (etk_bsdf_is_dielectric(m) &&
            etk_dielectric_is_delta(m.type == ETK_MAT_SMOOTH_DIELECTRIC, m.eta));
}

ETK_STRUCT_INLINE_FN float3 etk_bsdf_eval(EtkMaterial m, float3 wo, float3 wi) {
    float3 zero = make_float3(0.0f, 0.0f, 0.0f);
    if (etk_bsdf_is_dielectric(m))
        return etk_bsdf_is_delta(m) ? zero : etk_dielectric_eval(m.albedo, m.eta, m.alpha, wo, wi);
    if (wo.z <= 0.0f || wi.z <= 0.0f || m.type == ETK_MAT_MIRROR)
        return zero;
    if (m.type == ETK_MAT_DIFFUSE)
        return m.albedo * ETK_INV_PI;
    float3 h = normalize(wo + wi);
    float d = etk_ggx_d(h.z, m.alpha);
    float g = etk_smith_g1(wo.z, m.alpha) * etk_smith_g1(wi.z, m.alpha);
    float3 f = etk_microfacet_fresnel(m, dot(wi, h));
    float3 spec = f * (d * g / (4.0f * wo.z * wi.z));
    if (m.type == ETK_MAT_CONDUCTOR) // its albedo slot holds eta: no base
        return spec;
    return spec + m.albedo * (ETK_INV_PI * etk_base_coupling(m, wi.z, wo.z));
}

ETK_STRUCT_INLINE_FN float etk_bsdf_pdf(EtkMaterial m, float3 wo, float3 wi) {
    if (etk_bsdf_is_dielectric(m))
        return etk_bsdf_is_delta(m) ? 0.0f
                                    : etk_dielectric_pdf(m.eta, m.alpha, m.ggx_sampling, wo, wi);
    if (wo.z <= 0.0f || wi.z <= 0.0f || m.type == ETK_MAT_MIRROR)
        return 0.0f;
    float diffuse = wi.z * ETK_INV_PI;
    if (m.type == ETK_MAT_DIFFUSE)
        return diffuse;
    float3 h = normalize(wo + wi);
    // The half vector's density over the reflection's Jacobian 1 / (4 wo.h).
    float d = etk_ggx_d(h.z, m.alpha);
    float spec = m.ggx_sampling == ETK_GGX_VNDF ? etk_smith_g1(wo.z, m.alpha) * d / (4.0f * wo.z)
                                                : d * h.z / (4.0f * dot(wo, h));
    float ps = etk_specular_weight(m);
    return ps * spec + (1.0f - ps) * diffuse;
}

// An upper bound of etk_bsdf_pdf(m, wo, wi) over every wi, for this wo; ETK_PDF_UNBOUNDED where
// there is none to give (NDF-sampled GGX, whose density grows without bound as wo.h -> 0; glass;
// delta lobes). Diffuse: cos / pi <= 1 / pi. Visible-normal GGX: G1(wo) D(h) / (4 wo.z) with D at
// most max(alpha^2, 1 / alpha^2) / pi, reached at h = n (alpha < 1), so the bound is tight where
// n is visible from wo.
#define ETK_PDF_UNBOUNDED 3.0e38f
ETK_FN float etk_bsdf_pdf_bound(EtkMaterial m, float3 wo) {
    if (etk_bsdf_is_dielectric(m) || m.type == ETK_MAT_MIRROR)
        return ETK_PDF_UNBOUNDED;
    if (wo.z <= 0.0f)
        return 0.0f; // nothing reflects from below (etk_bsdf_pdf)
    if (m.type == ETK_MAT_DIFFUSE)
        return ETK_INV_PI;
    float ps = etk_specular_weight(m);
    if (m.ggx_sampling != ETK_GGX_VNDF && ps > 0.0f) // the NDF's share is unbounded
        return ETK_PDF_UNBOUNDED;
    float a2 = m.alpha * m.alpha;
    float d_max = fmax(a2, 1.0f / a2) * ETK_INV_PI;
    return ps * (etk_smith_g1(wo.z, m.alpha) * d_max / (4.0f * wo.z)) + (1.0f - ps) * ETK_INV_PI;
}

typedef struct {
    float3 wi;
    float3 weight; // f cos / pdf (for a delta lobe: the reflectance)
    float pdf;     // 0: no sample
    int delta;
} EtkBsdfSample;

// u: two values for the direction; lobe: one value choosing diffuse or specular.
ETK_STRUCT_INLINE_FN EtkBsdfSample etk_bsdf_sample(EtkMaterial m, float3 wo, float2 u, float lobe) {
    EtkBsdfSample s;
    s.weight = make_float3(0.0f, 0.0f, 0.0f);
    s.pdf = 0.0f;
    s.delta = 0;
    s.wi = make_float3(0.0f, 0.0f, 1.0f);
    if (etk_bsdf_is_dielectric(m)) {
        etk_dielectric_sample(m.albedo, m.eta, m.alpha, m.ggx_sampling,
                              m.type == ETK_MAT_SMOOTH_DIELECTRIC, wo, u, lobe, &s.wi, &s.weight,
                              &s.pdf, &s.delta);
        return s;
    }
    if (wo.z <= 0.0f)
        return s;
    if (m.type == ETK_MAT_MIRROR) {
        s.wi = make_float3(-wo.x, -wo.y, wo.z);
        s.weight = m.specular;
        s.pdf = 1.0f;
        s.delta = 1;
        return s;
    }
    float ps = etk_bsdf_is_glossy(m) ? etk_specular_weight(m) : 0.0f; // lobe >= 0: cosine
    if (lobe < ps) {
        float3 h = m.ggx_sampling == ETK_GGX_VNDF ? etk_sample_ggx_vndf(wo, m.alpha, u)
                                                  : etk_sample_ggx_ndf(m.alpha, u);
        s.wi = h * (2.0f * dot(wo, h)) - wo;
    } else {
        s.wi = etk_sample_cosine_hemisphere(u);
    }
    if (s.wi.z <= 0.0f)
        return s;
    s.pdf = etk_bsdf_pdf(m, wo, s.wi);
    if (s.pdf > 0.0f)
        s.weight = etk_bsdf_eval(m, wo, s.wi) * (s.wi.z / s.pdf);
    return s;
}

ETK_END

#endif
