// The BVH as it was before the SAH and 4-wide rewrite (builder of host/lib/prepare/bvh_build.cpp
// and traversal of kernels/bvh.h at main d2e3a75), kept verbatim in tools/bench only so that
// bench_rays measures before and after side by side in one process. Not used by the renderer;
// delete once served.
#pragma once
#include "kernels/bvh.h"
#include "load/scene.h"

#include <vector>

#define BASELINE_BVH_STACK 64
namespace baseline {
using namespace etk;
using etk::EtkHit;

struct Bvh {
    std::vector<etk::float4> nodes;
    std::vector<int> order;
    int depth = 0;
    double build_seconds = 0.0, sah_cost = 0.0;
};
Bvh build_bvh(const et::TriangleSoup& soup, int max_leaf = 4);

inline int b_child_meta(float4 lo) {
    return (int)as_uint(lo.w);
}
inline int b_child_is_leaf(float4 hi) {
    return (as_uint(hi.w) & 0x80000000u) != 0u;
}
inline int b_child_count(float4 hi) {
    return (int)(as_uint(hi.w) & 0x7fffffffu);
}

// Slab test against [0, tmax]; the slack keeps rays that graze a flat box from missing it.
inline int b_box_hit(float4 lo, float4 hi, float3 org, float3 inv_dir, float tmax, float* tnear) {
    float tx0 = (lo.x - org.x) * inv_dir.x, tx1 = (hi.x - org.x) * inv_dir.x;
    float ty0 = (lo.y - org.y) * inv_dir.y, ty1 = (hi.y - org.y) * inv_dir.y;
    float tz0 = (lo.z - org.z) * inv_dir.z, tz1 = (hi.z - org.z) * inv_dir.z;
    // Finite operands only (b_safe_inverse): plain min/max suffice.
    float tn = ETK_MAXF(ETK_MAXF(ETK_MINF(tx0, tx1), ETK_MINF(ty0, ty1)),
                        ETK_MAXF(ETK_MINF(tz0, tz1), 0.0f));
    float tf = ETK_MINF(ETK_MINF(ETK_MAXF(tx0, tx1), ETK_MAXF(ty0, ty1)),
                        ETK_MINF(ETK_MAXF(tz0, tz1), tmax));
    *tnear = tn;
    return tn <= tf * 1.00000024f;
}

// Moller-Trumbore; updates hit when closer than hit->t. Written on scalar components: OpenCL
// compilers otherwise do cross/dot as 3-wide vector shuffles, slower than scalar code on CPUs,
// and both back ends then round the very same operations.
inline int b_triangle_hit(const float4* tris, int prim, float3 org, float3 dir, EtkHit* hit) {
    float4 v0 = tris[3 * prim], e1 = tris[3 * prim + 1], e2 = tris[3 * prim + 2];
    float px = dir.y * e2.z - dir.z * e2.y; // p = dir x e2
    float py = dir.z * e2.x - dir.x * e2.z;
    float pz = dir.x * e2.y - dir.y * e2.x;
    float det = e1.x * px + e1.y * py + e1.z * pz;
    if (det == 0.0f || !isfinite(det))
        return 0;
    float inv = 1.0f / det;
    float sx = org.x - v0.x, sy = org.y - v0.y, sz = org.z - v0.z;
    float b1 = (sx * px + sy * py + sz * pz) * inv;
    if (b1 < 0.0f || b1 > 1.0f)
        return 0;
    float qx = sy * e1.z - sz * e1.y; // q = s x e1
    float qy = sz * e1.x - sx * e1.z;
    float qz = sx * e1.y - sy * e1.x;
    float b2 = (dir.x * qx + dir.y * qy + dir.z * qz) * inv;
    if (b2 < 0.0f || b1 + b2 > 1.0f)
        return 0;
    float t = (e2.x * qx + e2.y * qy + e2.z * qz) * inv;
    if (!(t > 0.0f) || !(t < hit->t))
        return 0;
    hit->t = t;
    hit->prim = prim;
    hit->b1 = b1;
    hit->b2 = b2;
    return 1;
}

inline float3 b_safe_inverse(float3 d) {
    float3 r;
    r.x = 1.0f / (fabs(d.x) > 1e-20f ? d.x : (d.x < 0.0f ? -1e-20f : 1e-20f));
    r.y = 1.0f / (fabs(d.y) > 1e-20f ? d.y : (d.y < 0.0f ? -1e-20f : 1e-20f));
    r.z = 1.0f / (fabs(d.z) > 1e-20f ? d.z : (d.z < 0.0f ? -1e-20f : 1e-20f));
    return r;
}

// Intersects the triangles of a leaf; returns 1 when any_hit and one was hit.
inline int b_leaf_hit(const float4* tris, float4 lo, float4 hi, float3 org, float3 dir, int any_hit,
                      EtkHit* hit) {
    int first = b_child_meta(lo), count = b_child_count(hi);
    for (int i = 0; i < count; ++i)
        if (b_triangle_hit(tris, first + i, org, dir, hit) && any_hit)
            return 1;
    return 0;
}

// Closest hit with t in (0, tmax), or any hit when any_hit != 0. Returns whether it hit.
inline int bvh_traverse(const float4* nodes, const float4* tris, float3 org, float3 dir, float tmax,
                        int any_hit, EtkHit* hit) {
    hit->t = tmax;
    hit->prim = -1;
    hit->b1 = hit->b2 = 0.0f;
    float3 inv_dir = b_safe_inverse(dir);
    int stack[BASELINE_BVH_STACK];
    int sp = 0;
    int node = 0;
    for (;;) {
        const float4* n = nodes + 4 * node;
        float4 lo0 = n[0], hi0 = n[1], lo1 = n[2], hi1 = n[3];
        float t0, t1;
        int in0 = b_box_hit(lo0, hi0, org, inv_dir, hit->t, &t0);
        int in1 = b_box_hit(lo1, hi1, org, inv_dir, hit->t, &t1);
        if (in0 && b_child_is_leaf(hi0)) {
            if (b_leaf_hit(tris, lo0, hi0, org, dir, any_hit, hit))
                return 1;
            in0 = 0;
        }
        if (in1 && b_child_is_leaf(hi1)) {
            if (t1 <= hit->t * 1.0000005f && b_leaf_hit(tris, lo1, hi1, org, dir, any_hit, hit))
                return 1;
            in1 = 0;
        }
        in0 = in0 && t0 <= hit->t * 1.0000005f; // slack: tnear and t round differently
        in1 = in1 && t1 <= hit->t * 1.0000005f;
        if (in0 && in1) {
            int near_child = b_child_meta(t0 <= t1 ? lo0 : lo1);
            int far_child = b_child_meta(t0 <= t1 ? lo1 : lo0);
            if (sp < BASELINE_BVH_STACK)
                stack[sp++] = far_child;
            node = near_child;
        } else if (in0) {
            node = b_child_meta(lo0);
        } else if (in1) {
            node = b_child_meta(lo1);
        } else {
            if (sp == 0)
                break;
            node = stack[--sp];
        }
    }
    return hit->prim >= 0;
}

} // namespace baseline
