// Closest-hit and any-hit traversal of the flattened 4-wide BVH the host builds
// (host/lib/prepare/bvh_build.cpp).
//
// Each node is eight float4 holding its four children in the lanes x, y, z, w (structure of
// arrays, so that the four box tests are the same operation on four lanes: what PoCL's
// work-item vectoriser and GCC's SLP vectoriser both handle): lo.x, lo.y, lo.z, hi.x, hi.y, hi.z,
// meta, flags; integers are stored as float bits. An inner child has flags 0 and meta = its node
// index. A leaf child has flags = 0x80000000 | its number of packets (below) and meta = its
// first packet; leaves are intersected straight from their parent, so a leaf costs no node fetch.
// An unused lane is an empty leaf (no packet) with a point box. Node 0 is the root. Of the inner
// children that the ray enters the nearest is visited next and the others are pushed far-first
// with their entry distance, so a popped node that lies beyond the closest hit found meanwhile is
// skipped without a fetch. The host keeps the tree shallow enough for ETK_BVH_STACK (at most
// 1 + 3 x depth entries).
//
// A leaf's triangles lie in packets of four, ETK_BVH_PACKET float4 each, again one triangle per
// lane: v0.x, v0.y, v0.z, v1.x, ..., v2.z and the triangle's index; an unused lane has index -1
// and three zero vertices, which no ray hits (determinant 0). The packets are the traversal's only
// triangle data.
//
// The triangle test is watertight (Woop, Benthin and Wald 2013): the vertices are moved into a
// frame where the ray is the +z axis, by a translation and a shear that depend on the ray alone,
// so a vertex shared by several triangles has the same sheared coordinates in each, and an edge
// shared by two triangles has edge functions of exactly opposite sign (each is a difference of
// the same two products, no fused multiply-add: compat.h). A ray through an edge or a vertex
// therefore hits at least one of the triangles around it. Moller-Trumbore, used before, computed
// each triangle's edges and barycentrics on its own, and let a ray aimed at shared edges and
// vertices through a closed mesh about once in ten (Bvh.ClosedMeshesHaveNoCracks): light leaked
// into closed spheres and rooms.
#ifndef ETK_BVH_H
#define ETK_BVH_H
#include "compat.h"

#define ETK_BVH_STACK 96
#define ETK_BVH_NODE 8    // float4 per node
#define ETK_BVH_PACKET 10 // float4 per packet of four triangles
// A packet's rows (float4 each, one lane per triangle): v0 x, y, z, then v1, v2, the index.
#define ETK_PACKET_V0 0
#define ETK_PACKET_V1 3
#define ETK_PACKET_V2 6
#define ETK_PACKET_PRIM 9

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
            1.000001f;
}

// The ray in the watertight test's frame: kz the axis of the direction's largest component, kx
// and ky the other two (swapped where that component is negative, which keeps the triangles'
// winding), the shear (sx, sy) that takes the direction onto the kz axis and sz = 1 / d[kz], and
// the origin's coordinates in that order. Made once per ray.
typedef struct {
    float3 org, dir; // as given, for the distance to a triangle that is hit
    int kx, ky, kz;
    float sx, sy, sz;
    float ox, oy, oz;
} EtkShearedRay;

ETK_FN float etk_axis(float3 v, int k) {
    return k == 0 ? v.x : (k == 1 ? v.y : v.z);
}

ETK_FN EtkShearedRay etk_sheared_ray(float3 org, float3 dir) {
    EtkShearedRay r;
    r.org = org;
    r.dir = dir;
    float ax = fabs(dir.x), ay = fabs(dir.y), az = fabs(dir.z);
    r.kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    r.kx = r.kz == 2 ? 0 : r.kz + 1;
    r.ky = r.kx == 2 ? 0 : r.kx + 1;
    float dz = etk_axis(dir, r.kz);
    if (dz < 0.0f) {
        int k = r.kx;
        r.kx = r.ky;
        r.ky = k;
    }
    r.sz = 1.0f / dz; // a zero direction: infinite, and every test below fails
    r.sx = etk_axis(dir, r.kx) * r.sz;
    r.sy = etk_axis(dir, r.ky) * r.sz;
    r.ox = etk_axis(org, r.kx);
    r.oy = etk_axis(org, r.ky);
    r.oz = etk_axis(org, r.kz);
    return r;
}

// Whether a triangle test hit: the edge functions u, v, w all of one sign (a zero counts as
// either: the ray passes through the edge, and both triangles there take it), a non-degenerate
// triangle (det = u + v + w non-zero and finite), t in (0, tmax) up to its rounding error terr
// (the estimate's sum cancels for triangles far larger than their distance: a ground quad 1e9
// wide seen from 1 unit lost most of its hits; the hit lane computes the distance it keeps). One
// expression for a lane (floats: 0 or 1) and for four lanes at once (etk_lanes: a mask per lane),
// so the two can never disagree.
#define ETK_TRIANGLE_HIT(u, v, w, det, t, terr, tmax, zero)                                        \
    ((((u >= zero) & (v >= zero) & (w >= zero)) | ((u <= zero) & (v <= zero) & (w <= zero))) &     \
     (det != zero) & (det - det == zero) & (t + terr > zero) & (t - terr < tmax))

// The vertices of the triangle in `slot` (packet index x 4 + lane) of the packets.
ETK_FN void etk_packet_triangle(ETK_GLOBAL const float4* packets, int slot, float3* v0, float3* v1,
                                float3* v2) {
    int lane = slot & 3;
    ETK_GLOBAL const float* pk = (ETK_GLOBAL const float*)(packets + (slot >> 2) * ETK_BVH_PACKET);
    *v0 = make_float3(pk[4 * ETK_PACKET_V0 + lane], pk[4 * ETK_PACKET_V0 + 4 + lane],
                      pk[4 * ETK_PACKET_V0 + 8 + lane]);
    *v1 = make_float3(pk[4 * ETK_PACKET_V1 + lane], pk[4 * ETK_PACKET_V1 + 4 + lane],
                      pk[4 * ETK_PACKET_V1 + 8 + lane]);
    *v2 = make_float3(pk[4 * ETK_PACKET_V2 + lane], pk[4 * ETK_PACKET_V2 + 4 + lane],
                      pk[4 * ETK_PACKET_V2 + 8 + lane]);
}

// One lane of a packet test: the hit is taken when closer than hit->t (so of two triangles at
// the same distance the one tested first keeps it). Its distance is the ray's to the triangle's
// plane, from the edges in the scene's coordinates (as Moller-Trumbore has it): the edge
// functions' t, from vertices relative to the ray's origin, loses the digits of the distance
// over the triangle's size (a triangle 1e-6 the size of its distance is placed ~10% off), which
// the sign tests tolerate but the closest hit's choice and the boxes' culling do not.
ETK_FORCE_INLINE_FN int etk_triangle_lane(ETK_GLOBAL const float4* pk, int lane, EtkShearedRay r,
                                          float u, float v, float w, float det, float t0,
                                          float terr, float prim, EtkHit* hit) {
    if (!ETK_TRIANGLE_HIT(u, v, w, det, t0, terr, hit->t * 2.0f, 0.0f))
        return 0;
    float3 v0, v1, v2;
    etk_packet_triangle(pk, lane, &v0, &v1, &v2); // slot `lane` of this packet
    float3 n = cross(v1 - v0, v2 - v0);
    float t = dot(v0 - r.org, n) / dot(r.dir, n);
    if (!(t > 0.0f && t < hit->t))
        return 0;
    float inv = 1.0f / det;
    float b1 = v * inv, b2 = w * inv;
    hit->t = t;
    hit->prim = (int)as_uint(prim);
    hit->b1 = b1;
    hit->b2 = b2;
    return 1;
}

// The watertight test (top) on the four triangles of a packet at once: each step one vector
// operation on both back ends, every lane rounded as a test of its triangle alone would be. The
// lanes are then taken in order, as one-by-one tests would take them. Returns 1 when any_hit and
// one was hit. The ray is broadcast here rather than passed broadcast: fewer live vectors across
// the traversal loop, which PoCL's code otherwise keeps on the stack.
ETK_FORCE_INLINE_FN int etk_packet_hit(ETK_GLOBAL const float4* pk, EtkShearedRay r, int any_hit,
                                       EtkHit* hit) {
    float4 ox = make_float4(r.ox, r.ox, r.ox, r.ox), oy = make_float4(r.oy, r.oy, r.oy, r.oy);
    float4 oz = make_float4(r.oz, r.oz, r.oz, r.oz);
    float4 sx = make_float4(r.sx, r.sx, r.sx, r.sx), sy = make_float4(r.sy, r.sy, r.sy, r.sy);
    // The vertices relative to the origin, sheared: the ray is then the kz axis.
    float4 az = pk[ETK_PACKET_V0 + r.kz] - oz, bz = pk[ETK_PACKET_V1 + r.kz] - oz,
           cz = pk[ETK_PACKET_V2 + r.kz] - oz;
    float4 ax = (pk[ETK_PACKET_V0 + r.kx] - ox) - sx * az,
           ay = (pk[ETK_PACKET_V0 + r.ky] - oy) - sy * az;
    float4 bx = (pk[ETK_PACKET_V1 + r.kx] - ox) - sx * bz,
           by = (pk[ETK_PACKET_V1 + r.ky] - oy) - sy * bz;
    float4 cx = (pk[ETK_PACKET_V2 + r.kx] - ox) - sx * cz,
           cy = (pk[ETK_PACKET_V2 + r.ky] - oy) - sy * cz;
    // Edge functions: twice the signed areas seen along the ray, of edges bc, ca and ab.
    float4 u = cx * by - cy * bx;
    float4 v = ax * cy - ay * cx;
    float4 w = bx * ay - by * ax;
    float4 det = u + v + w;
    float4 t = (u * az + v * bz + w * cz) * make_float4(r.sz, r.sz, r.sz, r.sz) / det;
    // Its rounding error: a few ulps of the sum's largest terms, over det.
    float4 terr = (fabs(u * az) + fabs(v * bz) + fabs(w * cz)) *
                  (make_float4(1e-6f, 1e-6f, 1e-6f, 1e-6f) * fabs(r.sz)) / fabs(det);
    // Most packets are missed by every lane: one vector test decides that, without a branch
    // per lane. Its distance is a first estimate, taken with slack: etk_triangle_lane computes
    // the one the hit keeps.
    etk_lanes zero = etk_lanes_splat(0.0f);
    if (!etk_any_lane(ETK_TRIANGLE_HIT(etk_lanes_of(u), etk_lanes_of(v), etk_lanes_of(w),
                                       etk_lanes_of(det), etk_lanes_of(t), etk_lanes_of(terr),
                                       etk_lanes_splat(hit->t * 2.0f), zero)))
        return 0;
    float4 prim = pk[ETK_PACKET_PRIM];
    return (etk_triangle_lane(pk, 0, r, u.x, v.x, w.x, det.x, t.x, terr.x, prim.x, hit) &&
            any_hit) ||
           (etk_triangle_lane(pk, 1, r, u.y, v.y, w.y, det.y, t.y, terr.y, prim.y, hit) &&
            any_hit) ||
           (etk_triangle_lane(pk, 2, r, u.z, v.z, w.z, det.z, t.z, terr.z, prim.z, hit) &&
            any_hit) ||
           (etk_triangle_lane(pk, 3, r, u.w, v.w, w.w, det.w, t.w, terr.w, prim.w, hit) && any_hit);
}

ETK_FN float3 etk_safe_inverse(float3 d) {
    float3 r;
    r.x = 1.0f / (fabs(d.x) > 1e-20f ? d.x : (d.x < 0.0f ? -1e-20f : 1e-20f));
    r.y = 1.0f / (fabs(d.y) > 1e-20f ? d.y : (d.y < 0.0f ? -1e-20f : 1e-20f));
    r.z = 1.0f / (fabs(d.z) > 1e-20f ? d.z : (d.z < 0.0f ? -1e-20f : 1e-20f));
    return r;
}

// Intersects the packets of a leaf; returns 1 when any_hit and one was hit. Inlined natively: as
// a call, GCC passes its vectors through memory (native traversal ~10% slower). A call in PoCL
// (compat.h, ETK_CPU_CALL_FN). The ray by value: by pointer, GCC's inlined code kept less of it
// in registers (native ~5% slower), and PoCL was no faster for the copy it saves.
ETK_CPU_CALL_FN int etk_leaf_hit(ETK_GLOBAL const float4* packets, int first, int count,
                                 EtkShearedRay r, int any_hit, EtkHit* hit) {
    for (int i = 0; i < count; ++i)
        if (etk_packet_hit(packets + ETK_BVH_PACKET * (first + i), r, any_hit, hit))
            return 1;
    return 0;
}

// Pushes an entered inner child in stack sorted order: entry distances decrease towards the
// top, so the nearest is popped first, and of equal distances the later lane. The host keeps the
// stack within ETK_BVH_STACK (see the top); `base` is where this node's pushes began.
ETK_FORCE_INLINE_FN void etk_bvh_push(int child, float t, int* stack, float* stack_t, int base,
                                      int* sp) {
    int j = *sp;
    if (j >= ETK_BVH_STACK) // never, for trees the host builds
        return;
    while (j > base && stack_t[j - 1] < t) { // insertion: at most three moves
        stack[j] = stack[j - 1];
        stack_t[j] = stack_t[j - 1];
        --j;
    }
    stack[j] = child;
    stack_t[j] = t;
    *sp = *sp + 1;
}

// Two entered inner children, lanes a < b: pushes the far one and returns the near one, which
// the sorted pushes would pop next (of equal distances the later lane). A branch, not a select:
// the near child's index then does not wait for the compare.
ETK_FORCE_INLINE_FN int etk_bvh_near_far(ETK_GLOBAL const float* meta, float4 tn, int a, int b,
                                         int* stack, float* stack_t, int* sp) {
    float ta = etk_lane(tn, a), tb = etk_lane(tn, b);
    int j = *sp;
    if (j >= ETK_BVH_STACK) // never, for trees the host builds
        return (int)as_uint(meta[ta < tb ? a : b]);
    *sp = j + 1;
    if (ta < tb) {
        stack[j] = (int)as_uint(meta[b]);
        stack_t[j] = tb;
        return (int)as_uint(meta[a]);
    }
    stack[j] = (int)as_uint(meta[a]);
    stack_t[j] = ta;
    return (int)as_uint(meta[b]);
}

// The inner children entered (bit mask `inner` of the lanes, entry distances tn, child indices
// meta[lane]): pushes all but the nearest and returns it, the node to visit next (-1: none).
// One or two children, most nodes, take a branch per mask with the lanes as constants: a
// predicted branch then loads the next node before the box test is done, where a lane index
// computed from the mask would wait for the test (camera rays ~10% slower that way).
ETK_FORCE_INLINE_FN int etk_bvh_next(ETK_GLOBAL const float* meta, float4 tn, uint inner,
                                     int* stack, float* stack_t, int* sp) {
    if (!inner)
        return -1;
    if (inner == 1u || inner == 2u || inner == 4u || inner == 8u)
        return (int)as_uint(
            inner == 1u ? meta[0] : (inner == 2u ? meta[1] : (inner == 4u ? meta[2] : meta[3])));
    if (inner == 3u)
        return etk_bvh_near_far(meta, tn, 0, 1, stack, stack_t, sp);
    if (inner == 5u)
        return etk_bvh_near_far(meta, tn, 0, 2, stack, stack_t, sp);
    if (inner == 6u)
        return etk_bvh_near_far(meta, tn, 1, 2, stack, stack_t, sp);
    if (inner == 9u)
        return etk_bvh_near_far(meta, tn, 0, 3, stack, stack_t, sp);
    if (inner == 10u)
        return etk_bvh_near_far(meta, tn, 1, 3, stack, stack_t, sp);
    if (inner == 12u)
        return etk_bvh_near_far(meta, tn, 2, 3, stack, stack_t, sp);
    int base = *sp;
    do {
        int i = etk_lowest_bit(inner);
        inner &= inner - 1u;
        etk_bvh_push((int)as_uint(meta[i]), etk_lane(tn, i), stack, stack_t, base, sp);
    } while (inner);
    *sp = *sp - 1;
    return stack[*sp];
}

// How far the ray still looks: the closest hit so far, with slack (a box's entry distance and a
// triangle's t round differently, so a child entered at the hit's own distance stays in).
ETK_FORCE_INLINE_FN float etk_bvh_reach(const EtkHit* hit) {
    return hit->t * 1.0000005f;
}

// Closest hit with t in (0, tmax), or any hit when any_hit != 0. Returns whether it hit.
// A node's lanes are tested at once and its entered children taken from bit masks: first its
// leaves, in lane order, each while its entry distance is still within the closest hit (the
// order of one-by-one lanes, which decides exact ties); then its inner children, the nearest
// visited next without a trip through the stack.
ETK_CL_NOINLINE_FN int etk_bvh_traverse(ETK_GLOBAL const float4* nodes,
                                        ETK_GLOBAL const float4* packets, float3 org, float3 dir,
                                        float tmax, int any_hit, EtkHit* hit) {
    hit->t = tmax;
    hit->prim = -1;
    hit->b1 = hit->b2 = 0.0f;
    float3 inv_dir = etk_safe_inverse(dir);
    EtkShearedRay sr = etk_sheared_ray(org, dir);
    float4 ox = make_float4(org.x, org.x, org.x, org.x),
           oy = make_float4(org.y, org.y, org.y, org.y);
    float4 oz = make_float4(org.z, org.z, org.z, org.z);
    float4 ix = make_float4(inv_dir.x, inv_dir.x, inv_dir.x, inv_dir.x);
    float4 iy = make_float4(inv_dir.y, inv_dir.y, inv_dir.y, inv_dir.y);
    float4 iz = make_float4(inv_dir.z, inv_dir.z, inv_dir.z, inv_dir.z);
    int stack[ETK_BVH_STACK];
    float stack_t[ETK_BVH_STACK];
    int sp = 0;
    int node = 0; // the node to visit; -1: pop one
    for (;;) {
        if (node < 0) {
            if (sp == 0)
                break;
            --sp;
            if (!(stack_t[sp] <= etk_bvh_reach(hit)))
                continue; // entered beyond the closest hit found since it was pushed
            node = stack[sp];
        }
        ETK_GLOBAL const float4* nd = nodes + ETK_BVH_NODE * node;
        float4 tn, tf;
        etk_box_hit4(nd, ox, oy, oz, ix, iy, iz, hit->t, &tn, &tf);
        ETK_GLOBAL const float* meta = (ETK_GLOBAL const float*)(nd + 6); // lane i: meta[i]
        // Entered: tnear <= tfar and within the ray's reach.
        etk_lanes lim = etk_lanes_splat(etk_bvh_reach(hit));
        uint enter =
            etk_lane_bits((etk_lanes_of(tn) <= etk_lanes_of(tf)) & (etk_lanes_of(tn) <= lim));
        uint leaf = etk_sign_bits(nd[7]); // flags: the sign bit marks a leaf
        uint leaves = enter & leaf;
        if (leaves) {
            ETK_GLOBAL const float* flags = (ETK_GLOBAL const float*)(nd + 7);
            do {
                int i = etk_lowest_bit(leaves);
                leaves &= leaves - 1u;
                if (etk_lane(tn, i) <= etk_bvh_reach(hit) &&
                    etk_leaf_hit(packets, (int)as_uint(meta[i]),
                                 (int)(as_uint(flags[i]) & 0x7fffffffu), sr, any_hit, hit))
                    return 1;
            } while (leaves);
            lim = etk_lanes_splat(etk_bvh_reach(hit));
            enter &= etk_lane_bits(etk_lanes_of(tn) <= lim);
        }
        node = etk_bvh_next(meta, tn, enter & ~leaf, stack, stack_t, &sp);
    }
    return hit->prim >= 0;
}

ETK_END

#endif
