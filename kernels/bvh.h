// Closest-hit and any-hit traversal of the flattened BVH the host builds (host/lib/bvh.h).
//
// Node i is two float4: (bounds min, meta) and (bounds max, axis << 16 | count), the integers
// stored as float bits. Inner node: count 0, first child i+1, meta = second child, axis = split
// axis. Leaf: meta = first triangle, count > 0 triangles. An empty scene has one leaf holding one
// all-zero (never hit) triangle. The host keeps the tree shallower than ETK_BVH_STACK.
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

ETK_FN int etk_node_meta(float4 lo) {
    return (int)as_uint(lo.w);
}
ETK_FN int etk_node_count(float4 hi) {
    return (int)(as_uint(hi.w) & 0xffffu);
}
ETK_FN int etk_node_axis(float4 hi) {
    return (int)(as_uint(hi.w) >> 16);
}

// Slab test against [0, tmax]; the slack keeps rays that graze a flat box from missing it.
ETK_FN int etk_box_hit(float4 lo, float4 hi, float3 org, float3 inv_dir, float tmax) {
    float tx0 = (lo.x - org.x) * inv_dir.x, tx1 = (hi.x - org.x) * inv_dir.x;
    float ty0 = (lo.y - org.y) * inv_dir.y, ty1 = (hi.y - org.y) * inv_dir.y;
    float tz0 = (lo.z - org.z) * inv_dir.z, tz1 = (hi.z - org.z) * inv_dir.z;
    float tnear = fmax(fmax(fmin(tx0, tx1), fmin(ty0, ty1)), fmax(fmin(tz0, tz1), 0.0f));
    float tfar = fmin(fmin(fmax(tx0, tx1), fmax(ty0, ty1)), fmin(fmax(tz0, tz1), tmax));
    return tnear <= tfar * 1.00000024f;
}

// Moller-Trumbore; updates hit when closer than hit->t.
ETK_FN int etk_triangle_hit(ETK_GLOBAL const float4* tris, int prim, float3 org, float3 dir,
                            EtkHit* hit) {
    float4 a = tris[3 * prim], b = tris[3 * prim + 1], c = tris[3 * prim + 2];
    float3 v0 = make_float3(a.x, a.y, a.z), e1 = make_float3(b.x, b.y, b.z),
           e2 = make_float3(c.x, c.y, c.z);
    float3 p = cross(dir, e2);
    float det = dot(e1, p);
    if (det == 0.0f || !isfinite(det))
        return 0;
    float inv = 1.0f / det;
    float3 s = org - v0;
    float b1 = dot(s, p) * inv;
    if (b1 < 0.0f || b1 > 1.0f)
        return 0;
    float3 q = cross(s, e1);
    float b2 = dot(dir, q) * inv;
    if (b2 < 0.0f || b1 + b2 > 1.0f)
        return 0;
    float t = dot(e2, q) * inv;
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

// Closest hit with t in (0, tmax), or any hit when any_hit != 0. Returns whether it hit.
ETK_FN int etk_bvh_traverse(ETK_GLOBAL const float4* nodes, ETK_GLOBAL const float4* tris,
                            float3 org, float3 dir, float tmax, int any_hit, EtkHit* hit) {
    hit->t = tmax;
    hit->prim = -1;
    hit->b1 = hit->b2 = 0.0f;
    float3 inv_dir = etk_safe_inverse(dir);
    int neg[3] = {dir.x < 0.0f, dir.y < 0.0f, dir.z < 0.0f};
    int stack[ETK_BVH_STACK];
    int sp = 0;
    int node = 0;
    for (;;) {
        float4 lo = nodes[2 * node], hi = nodes[2 * node + 1];
        if (etk_box_hit(lo, hi, org, inv_dir, hit->t)) {
            int count = etk_node_count(hi);
            if (count > 0) {
                int first = etk_node_meta(lo);
                for (int i = 0; i < count; ++i)
                    if (etk_triangle_hit(tris, first + i, org, dir, hit) && any_hit)
                        return 1;
            } else {
                // Visit the child on the ray's near side of the split first.
                int second = etk_node_meta(lo);
                int near_child = node + 1, far_child = second;
                if (neg[etk_node_axis(hi)]) {
                    near_child = second;
                    far_child = node + 1;
                }
                if (sp < ETK_BVH_STACK)
                    stack[sp++] = far_child;
                node = near_child;
                continue;
            }
        }
        if (sp == 0)
            break;
        node = stack[--sp];
    }
    return hit->prim >= 0;
}

ETK_END

#endif
