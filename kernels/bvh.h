// Closest-hit and any-hit traversal of the flattened 4-wide BVH the host builds
// (host/lib/prepare/bvh_build.cpp).
//
// Each node is eight float4 holding its four children in the lanes x, y, z, w (structure of
// arrays, so that the four box tests are the same operation on four lanes: what PoCL's
// work-item vectoriser and GCC's SLP vectoriser both handle): lo.x, lo.y, lo.z, hi.x, hi.y, hi.z,
// meta, flags; integers are stored as float bits. An inner child has flags 0 and meta = its node
// index. A leaf child has flags = 0x80000000 | count and meta = its first triangle; leaves are
// intersected straight from their parent, so a leaf costs no node fetch. An unused lane is an
// empty leaf (count 0) with a point box. Node 0 is the root. Inner children that the ray enters
// are pushed far-first with their entry distance, so the nearest is visited next and a popped
// node that lies beyond the closest hit found meanwhile is skipped without a fetch. The host
// keeps the tree shallow enough for ETK_BVH_STACK (at most 1 + 3 x depth entries).
// Triangles are three float4 each: v0, edge1 = v1 - v0, edge2 = v2 - v0 (Moller-Trumbore).
#ifndef ETK_BVH_H
#define ETK_BVH_H
#include "compat.h"

#define ETK_BVH_STACK 96
#define ETK_BVH_NODE 8 // float4 per node

ETK_BEGIN

typedef struct {
    float t;      // distance along the ray; > tmax means no hit
    int prim;     // triangle index, -1 for none
    float b1, b2; // barycentrics of v1 and v2
} EtkHit;

// Slab tests of a node's four boxes against [0, tmax], lane-wise (one vector operation per step
// on both back ends): entry and exit distances. A lane is entered when tnear <= tfar * slack; the
// slack keeps rays that graze a flat box from missing it.
ETK_FN void etk_box_hit4(ETK_GLOBAL const float4* nd, float4 ox, float4 oy, float4 oz, float4 ix,
                         float4 iy, float4 iz, float tmax, float4* tnear, float4* tfar) {
    float4 tx0 = (nd[0] - ox) * ix, tx1 = (nd[3] - ox) * ix;
    float4 ty0 = (nd[1] - oy) * iy, ty1 = (nd[4] - oy) * iy;
    float4 tz0 = (nd[2] - oz) * iz, tz1 = (nd[5] - oz) * iz;
    // Finite operands only (etk_safe_inverse): plain min/max suffice.
    float4 zero = make_float4(0.0f, 0.0f, 0.0f, 0.0f);
    float4 tm = make_float4(tmax, tmax, tmax, tmax);
    *tnear = ETK_MAXF(ETK_MAXF(ETK_MINF(tx0, tx1), ETK_MINF(ty0, ty1)),
                      ETK_MAXF(ETK_MINF(tz0, tz1), zero));
    *tfar = ETK_MINF(ETK_MINF(ETK_MAXF(tx0, tx1), ETK_MAXF(ty0, ty1)),
                     ETK_MINF(ETK_MAXF(tz0, tz1), tm)) *
            1.00000024f;
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
ETK_FN int etk_leaf_hit(ETK_GLOBAL const float4* tris, int first, int count, float3 org, float3 dir,
                        int any_hit, EtkHit* hit) {
    for (int i = 0; i < count; ++i)
        if (etk_triangle_hit(tris, first + i, org, dir, hit) && any_hit)
            return 1;
    return 0;
}

// One lane of a node: a leaf the ray enters is intersected now (returns 1 for an any-hit
// query that found one); an inner child it enters is pushed, in stack sorted order: entry
// distances decrease towards the top, so the nearest is popped first. The host keeps the stack
// within ETK_BVH_STACK (see the top); `base` is where this node's pushes began.
ETK_FORCE_INLINE_FN int etk_bvh_lane(ETK_GLOBAL const float4* tris, int in, float t, float meta,
                                     float flags, float3 org, float3 dir, int any_hit, EtkHit* hit,
                                     int* stack, float* stack_t, int base, int* sp) {
    if (!in || !(t <= hit->t * 1.0000005f)) // slack: tnear and t round differently
        return 0;
    uint f = as_uint(flags);
    if (f & 0x80000000u)
        return etk_leaf_hit(tris, (int)as_uint(meta), (int)(f & 0x7fffffffu), org, dir, any_hit,
                            hit);
    int j = *sp;
    if (j >= ETK_BVH_STACK) // never, for trees the host builds
        return 0;
    while (j > base && stack_t[j - 1] < t) { // insertion: at most three moves
        stack[j] = stack[j - 1];
        stack_t[j] = stack_t[j - 1];
        --j;
    }
    stack[j] = (int)as_uint(meta);
    stack_t[j] = t;
    *sp = *sp + 1;
    return 0;
}

// Closest hit with t in (0, tmax), or any hit when any_hit != 0. Returns whether it hit.
ETK_FN int etk_bvh_traverse(ETK_GLOBAL const float4* nodes, ETK_GLOBAL const float4* tris,
                            float3 org, float3 dir, float tmax, int any_hit, EtkHit* hit) {
    hit->t = tmax;
    hit->prim = -1;
    hit->b1 = hit->b2 = 0.0f;
    float3 inv_dir = etk_safe_inverse(dir);
    float4 ox = make_float4(org.x, org.x, org.x, org.x),
           oy = make_float4(org.y, org.y, org.y, org.y);
    float4 oz = make_float4(org.z, org.z, org.z, org.z);
    float4 ix = make_float4(inv_dir.x, inv_dir.x, inv_dir.x, inv_dir.x);
    float4 iy = make_float4(inv_dir.y, inv_dir.y, inv_dir.y, inv_dir.y);
    float4 iz = make_float4(inv_dir.z, inv_dir.z, inv_dir.z, inv_dir.z);
    int stack[ETK_BVH_STACK];
    float stack_t[ETK_BVH_STACK];
    int sp = 1;
    stack[0] = 0;
    stack_t[0] = 0.0f;
    while (sp > 0) {
        --sp;
        if (!(stack_t[sp] <= hit->t * 1.0000005f))
            continue; // entered beyond the closest hit found since it was pushed
        ETK_GLOBAL const float4* nd = nodes + ETK_BVH_NODE * stack[sp];
        float4 tn, tf;
        etk_box_hit4(nd, ox, oy, oz, ix, iy, iz, hit->t, &tn, &tf);
        float4 meta = nd[6], flags = nd[7];
        int base = sp;
        if (etk_bvh_lane(tris, tn.x <= tf.x, tn.x, meta.x, flags.x, org, dir, any_hit, hit, stack,
                         stack_t, base, &sp) ||
            etk_bvh_lane(tris, tn.y <= tf.y, tn.y, meta.y, flags.y, org, dir, any_hit, hit, stack,
                         stack_t, base, &sp) ||
            etk_bvh_lane(tris, tn.z <= tf.z, tn.z, meta.z, flags.z, org, dir, any_hit, hit, stack,
                         stack_t, base, &sp) ||
            etk_bvh_lane(tris, tn.w <= tf.w, tn.w, meta.w, flags.w, org, dir, any_hit, hit, stack,
                         stack_t, base, &sp))
            return 1;
    }
    return hit->prim >= 0;
}

ETK_END

#endif
