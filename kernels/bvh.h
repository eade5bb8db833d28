// Closest-hit and any-hit traversal of the flattened BVH the host builds (host/lib/bvh.h).
//
// Each inner node is four float4 holding both children: (box min, meta) and (box max, flags)
// for the first child, then the same for the second; integers are stored as float bits. An inner
// child has flags 0 and meta = its node index. A leaf child has flags = 0x80000000 | count and
// meta = its first triangle; leaves are intersected straight from their parent, so a leaf costs
// no node fetch. Node 0 is the root (a scene of one leaf or none gets a root whose other child
// is an empty leaf). Both child boxes are tested together and the nearer is visited first. The
// host keeps the tree shallower than ETK_BVH_STACK.
// Triangles are three float4 each: v0, edge1 = v1 - v0, edge2 = v2 - v0 (Moller-Trumbore).
#ifndef ETK_BVH_H
#define ETK_BVH_H
#include "compat.h"

#define ETK_BVH_STACK 64

ETK_BEGIN

typedef struct {
    float t;      // distance along the ray; > tmax means no hit
    int prim;     // triangle index, -1 for none
    float b1, b2; // barycentrics of v1 and v2
} EtkHit;

ETK_FN int etk_child_meta(float4 lo) {
    return (int)as_uint(lo.w);
}
ETK_FN int etk_child_is_leaf(float4 hi) {
    return (as_uint(hi.w) & 0x80000000u) != 0u;
}
ETK_FN int etk_child_count(float4 hi) {
    return (int)(as_uint(hi.w) & 0x7fffffffu);
}

// Slab test against [0, tmax]; the slack keeps rays that graze a flat box from missing it.
ETK_FN int etk_box_hit(float4 lo, float4 hi, float3 org, float3 inv_dir, float tmax, float* tnear) {
    float tx0 = (lo.x - org.x) * inv_dir.x, tx1 = (hi.x - org.x) * inv_dir.x;
    float ty0 = (lo.y - org.y) * inv_dir.y, ty1 = (hi.y - org.y) * inv_dir.y;
    float tz0 = (lo.z - org.z) * inv_dir.z, tz1 = (hi.z - org.z) * inv_dir.z;
    // Finite operands only (etk_safe_inverse): plain min/max suffice.
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
ETK_FN int etk_triangle_hit(ETK_GLOBAL const float4* tris, int prim, float3 org, float3 dir,
                            EtkHit* hit) {
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

ETK_FN float3 etk_safe_inverse(float3 d) {
    float3 r;
    r.x = 1.0f / (fabs(d.x) > 1e-20f ? d.x : (d.x < 0.0f ? -1e-20f : 1e-20f));
    r.y = 1.0f / (fabs(d.y) > 1e-20f ? d.y : (d.y < 0.0f ? -1e-20f : 1e-20f));
    r.z = 1.0f / (fabs(d.z) > 1e-20f ? d.z : (d.z < 0.0f ? -1e-20f : 1e-20f));
    return r;
}

// Intersects the triangles of a leaf; returns 1 when any_hit and one was hit.
ETK_FN int etk_leaf_hit(ETK_GLOBAL const float4* tris, float4 lo, float4 hi, float3 org, float3 dir,
                        int any_hit, EtkHit* hit) {
    int first = etk_child_meta(lo), count = etk_child_count(hi);
    for (int i = 0; i < count; ++i)
        if (etk_triangle_hit(tris, first + i, org, dir, hit) && any_hit)
            return 1;
    return 0;
}

// Closest hit with t in (0, tmax), or any hit when any_hit != 0. Returns whether it hit.
ETK_FN int etk_bvh_traverse(ETK_GLOBAL const float4* nodes, ETK_GLOBAL const float4* tris,
                            float3 org, float3 dir, float tmax, int any_hit, EtkHit* hit) {
    hit->t = tmax;
    hit->prim = -1;
    hit->b1 = hit->b2 = 0.0f;
    float3 inv_dir = etk_safe_inverse(dir);
    int stack[ETK_BVH_STACK];
    int sp = 0;
    int node = 0;
    for (;;) {
        ETK_GLOBAL const float4* n = nodes + 4 * node;
        float4 lo0 = n[0], hi0 = n[1], lo1 = n[2], hi1 = n[3];
        float t0, t1;
        int in0 = etk_box_hit(lo0, hi0, org, inv_dir, hit->t, &t0);
        int in1 = etk_box_hit(lo1, hi1, org, inv_dir, hit->t, &t1);
        if (in0 && etk_child_is_leaf(hi0)) {
            if (etk_leaf_hit(tris, lo0, hi0, org, dir, any_hit, hit))
                return 1;
            in0 = 0;
        }
        if (in1 && etk_child_is_leaf(hi1)) {
            if (t1 <= hit->t * 1.0000005f && etk_leaf_hit(tris, lo1, hi1, org, dir, any_hit, hit))
                return 1;
            in1 = 0;
        }
        in0 = in0 && t0 <= hit->t * 1.0000005f; // slack: tnear and t round differently
        in1 = in1 && t1 <= hit->t * 1.0000005f;
        if (in0 && in1) {
            int near_child = etk_child_meta(t0 <= t1 ? lo0 : lo1);
            int far_child = etk_child_meta(t0 <= t1 ? lo1 : lo0);
            if (sp < ETK_BVH_STACK)
                stack[sp++] = far_child;
            node = near_child;
        } else if (in0) {
            node = etk_child_meta(lo0);
        } else if (in1) {
            node = etk_child_meta(lo1);
        } else {
            if (sp == 0)
                break;
            node = stack[--sp];
        }
    }
    return hit->prim >= 0;
}

ETK_END

#endif
