// What every shading stage starts from: the camera ray of a sample, and the surface at a hit
// with its shading frame, material and the origin of rays that leave it.
#ifndef ETK_SURFACE_H
#define ETK_SURFACE_H
#include "bsdf.h"
#include "compat.h"
#include "bvh.h"
#include "params.h"
#include "path_state.h"
#include "sampler.h"
#include "texture_lookup.h"

ETK_BEGIN

ETK_FN float3 etk_xyz(float4 v) {
    return make_float3(v.x, v.y, v.z);
}
ETK_FN float4 etk_f4(float3 v, float w) {
    return make_float4(v.x, v.y, v.z, w);
}
ETK_FN float3 etk_p3(const float* p) {
    return make_float3(p[0], p[1], p[2]);
}

ETK_FORCE_INLINE_FN float2 etk_dims(EtkParams p, int pixel, uint pair) {
    return etk_sample_pair(p.sampler, p.seed, (uint)pixel, p.sample_index, pair);
}

// The camera ray direction of sample p.sample_index of `pixel` (pixel jitter from pair 0).
ETK_FN float3 etk_camera_dir(EtkParams p, int pixel) {
    float2 j = etk_dims(p, pixel, 0u);
    float px = (float)(pixel % p.width) + j.x, py = (float)(pixel / p.width) + j.y;
    float sx = 2.0f * px / (float)p.width - 1.0f, sy = 1.0f - 2.0f * py / (float)p.height;
    return normalize(etk_p3(p.forward) + etk_p3(p.right) * sx + etk_p3(p.up) * sy);
}

// A surface point's shading frame (t, b, ns), the geometric normal facing the viewer, the
// outgoing direction in the frame, the material and the origin of rays leaving it: `origin` on
// the viewer's side, `origin_back` on the other (rays a dielectric transmits).
typedef struct {
    float3 t, b, ns, ng, origin, wo;
    EtkMaterial m;
    float3 origin_back;
} EtkSurface;

// Where the rays that leave a surface start: its geometric normal on the viewer's side, the origin
// on that side and the one on the other (rays a dielectric transmits).
typedef struct {
    float3 ng, origin, origin_back;
} EtkRayStart;
// The origin of a ray in world direction wi: on wi's side of the geometric surface, so that a
// transmitted ray does not hit the surface it crossed.
ETK_FN float3 etk_start_towards(EtkRayStart r, float3 wi_world) {
    return dot(wi_world, r.ng) < 0.0f ? r.origin_back : r.origin;
}
ETK_FN EtkRayStart etk_surface_start(EtkSurface s) {
    EtkRayStart r;
    r.ng = s.ng;
    r.origin = s.origin;
    r.origin_back = s.origin_back;
    return r;
}
ETK_FN float3 etk_surface_origin(EtkSurface s, float3 wi_world) {
    return etk_start_towards(etk_surface_start(s), wi_world);
}

// Whether a direction's local cosine wz (shading frame) and its world side (dwg = dot(wi, ng))
// agree: a direction on one side of the shading surface but the other of the geometric one
// would leak light through the shading normal's tilt. Both above: reflection; both below:
// transmission (only dielectrics evaluate to non-zero there).
ETK_FN int etk_same_side(float wz, float dwg) {
    return (wz > 0.0f && dwg > 0.0f) || (wz < 0.0f && dwg < 0.0f);
}
// The same for a light sample at a surface of material m, which only a dielectric can receive
// from below: the test rejects the other half of the sphere before anything is evaluated.
ETK_FN int etk_light_side_ok(EtkMaterial m, float wz, float dwg) {
    return etk_same_side(wz, dwg) && (wz > 0.0f || etk_bsdf_is_dielectric(m));
}

// Where a hit is, and how large the coordinates its rounding is relative to. Two ways: from
// the triangle's vertices and the hit's barycentrics (read back from its packet, bvh.h), on the
// triangle's plane up to a few ulps of the vertices' coordinates, whatever the ray's origin (a
// camera far away would need offsets the size of the scene from o + d t); or o + d t, with t
// from the plane (etk_triangle_lane), off it by ulps of the origin's and the point's coordinates
// and of the plane's own terms, which is the smaller for a large triangle seen from near: a
// ground quad 1e6 wide placed its hits to ulps of 5e5, and the offsets (below) lifted shadow
// rays 5 units off it, so a unit sphere on it cast no shadow. *scale: the magnitude the chosen
// point's error is relative to.
ETK_FN float3 etk_hit_point(EtkScene S, float3 o, float3 d, EtkHit h, float* scale) {
    float3 v0, v1, v2;
    etk_packet_triangle(S.packets, S.packet_slot[h.prim], &v0, &v1, &v2);
    float3 e1 = v1 - v0, e2 = v2 - v0;
    float3 ext = make_float3(fmax(fmax(fabs(v0.x), fabs(v1.x)), fabs(v2.x)),
                             fmax(fmax(fabs(v0.y), fabs(v1.y)), fabs(v2.y)),
                             fmax(fmax(fabs(v0.z), fabs(v1.z)), fabs(v2.z)));
    float vertex_scale = fmax(fmax(ext.x, ext.y), ext.z);
    float3 pr = o + d * h.t;
    float3 n = etk_xyz(S.face_normals[h.prim]), a = v0 - o;
    float ray_scale = fmax(
        fmax(fmax(fabs(o.x), fabs(o.y)), fmax(fabs(o.z), fabs(pr.x))),
        fmax(fmax(fabs(pr.y), fabs(pr.z)), fabs(a.x * n.x) + fabs(a.y * n.y) + fabs(a.z * n.z)));
    if (ray_scale < vertex_scale && isfinite(ray_scale)) {
        *scale = ray_scale;
        return pr;
    }
    *scale = vertex_scale;
    return v0 + e1 * h.b1 + e2 * h.b2;
}

// The shading normal bent, where needed, so that it reflects wo above the geometric surface.
// Interpolated normals tilt away from the viewer near silhouettes: the mirror reflection of wo
// then points into the surface and is lost, and where wo itself is below the shading normal's
// hemisphere the BSDF sees nothing at all (a smooth mirror sphere's rim lost up to 5% in a
// furnace, and an index-1 glass sphere showed a dark ring). There the reflected direction is
// raised to a small elevation t above the geometric plane, keeping its azimuth, and the normal
// becomes the half vector of wo and it. Elsewhere the normal is returned as it is.
ETK_FN float3 etk_reflecting_normal(float3 ns, float3 ng, float3 wo) {
    float wg = dot(wo, ng);
    float3 r = ns * (2.0f * dot(ns, wo)) - wo;
    float t = fmin(0.9f * wg, 0.01f);
    if (!(wg > 0.0f) || dot(r, ng) >= t)
        return ns;
    float3 rt = r - ng * dot(r, ng);
    float lt = length(rt);
    if (!(lt > 1e-6f)) { // straight down: the azimuth of wo's reflection in the true surface
        rt = ng * wg - wo;
        lt = length(rt);
        if (!(lt > 1e-6f))
            return ng;
    }
    float3 r2 = rt * (sqrt(fmax(0.0f, 1.0f - t * t)) / lt) + ng * t;
    float3 h = wo + r2;
    float lh = length(h);
    return lh > 0.0f ? h / lh : ng;
}

// The geometric normal of triangle prim on the side a ray in direction d sees; *front: whether
// the triangle's winding faces the ray.
ETK_FN float3 etk_facing_normal(EtkScene S, int prim, float3 d, int* front) {
    float3 g = etk_xyz(S.face_normals[prim]);
    *front = dot(g, -d) >= 0.0f;
    return *front ? g : -g;
}

// The normals at barycentrics (b1, b2) of triangle prim hit by a ray in direction d: the
// interpolated shading normal, returned, and the geometric one, *ng, both on the side that faces
// the viewer (surfaces are two-sided); *front: whether the triangle's winding faces the viewer.
ETK_FN float3 etk_shading_normal(EtkScene S, int prim, float b1, float b2, float3 d, float3* ng,
                                 int* front) {
    float3 g = etk_xyz(S.face_normals[prim]);
    float b0 = 1.0f - b1 - b2;
    float3 ns = etk_xyz(S.normals[3 * prim]) * b0 + etk_xyz(S.normals[3 * prim + 1]) * b1 +
                etk_xyz(S.normals[3 * prim + 2]) * b2;
    float nl = length(ns);
    ns = nl > 0.0f && isfinite(nl) ? ns / nl : g;
    g = etk_facing_normal(S, prim, d, front);
    if (dot(ns, g) < 0.0f)
        ns = -ns;
    *ng = g;
    return etk_reflecting_normal(ns, g, -d);
}

// The ray start of a hit at pos, its coordinates' magnitude `extent` (etk_hit_point), geometric
// normal ng. The offset follows the hit point's rounding error off the triangle's plane, a few
// ulps of the coordinates etk_hit_point names (the vertices', or the ray's where those are
// smaller): relative, with no absolute floor, so a scene renders alike at any unit, position and
// camera distance, and however large its triangles (tests/kernels/surface_test.cpp). The tiny
// floor keeps a triangle at the origin off zero.
ETK_FN EtkRayStart etk_ray_start(EtkParams p, float3 pos, float extent, float3 ng) {
    float scale = fmax(extent, 1.0e-30f);
    EtkRayStart r;
    r.ng = ng;
    r.origin = pos + ng * (p.ray_epsilon * scale);
    r.origin_back = pos - ng * (p.ray_epsilon * scale);
    return r;
}
// The ray start of the closest hit h of a ray (o, d), without the rest of its surface.
ETK_FN EtkRayStart etk_hit_start(EtkScene S, EtkParams p, float3 o, float3 d, EtkHit h) {
    float extent;
    float3 pos = etk_hit_point(S, o, d, h, &extent);
    int front;
    return etk_ray_start(p, pos, extent, etk_facing_normal(S, h.prim, d, &front));
}

// The surface at the closest hit h of a ray in direction d. Surfaces are two-sided; the shading
// normal is flipped to the geometric normal's side.
ETK_FN EtkSurface etk_surface_at(EtkScene S, EtkParams p, float3 o, float3 d, EtkHit h) {
    EtkSurface s;
    int prim = h.prim;
    float extent;
    float3 pos = etk_hit_point(S, o, d, h, &extent);
    float3 ng;
    int front;
    float3 ns = etk_shading_normal(S, prim, h.b1, h.b2, d, &ng, &front);
    float3 wo_world = -d;
    etk_make_frame(ns, &s.t, &s.b);
    s.ns = ns;
    s.ng = ng;
    s.wo = etk_to_local(wo_world, s.t, s.b, ns);
    s.m = etk_material_load(S.materials, S.tri_material[prim]);
    s.m = etk_material_textured(S, s.m, S.tri_material[prim], prim, h.b1, h.b2);
    s.m.ggx_sampling = p.bsdf_sampling;
    // A dielectric's outside is its front face (counter-clockwise winding, the OBJ convention):
    // from the back, the ray is inside and sees 1 / ior.
    if (!front && etk_bsdf_is_dielectric(s.m))
        s.m.eta = 1.0f / s.m.eta;
    EtkRayStart r = etk_ray_start(p, pos, extent, ng);
    s.origin = r.origin;
    s.origin_back = r.origin_back;
    return s;
}

// The hit a path's ray made (its hit record, stored by the intersect stage), the surface there,
// and its ray start alone.
ETK_FN EtkHit etk_path_hit(EtkPaths P, int slot) {
    float4 h4 = P.hit[slot];
    EtkHit h;
    h.t = h4.x;
    h.prim = (int)as_uint(h4.y);
    h.b1 = h4.z;
    h.b2 = h4.w;
    return h;
}
ETK_FN EtkSurface etk_path_surface(EtkScene S, EtkPaths P, EtkParams p, int slot) {
    return etk_surface_at(S, p, etk_xyz(P.ray_o[slot]), etk_xyz(P.ray_d[slot]),
                          etk_path_hit(P, slot));
}
ETK_FN EtkRayStart etk_path_start(EtkScene S, EtkPaths P, EtkParams p, int slot) {
    return etk_hit_start(S, p, etk_xyz(P.ray_o[slot]), etk_xyz(P.ray_d[slot]),
                         etk_path_hit(P, slot));
}

ETK_END

#endif
