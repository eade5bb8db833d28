// Closest-hit and any-hit traversal of the flattened 8-wide BVH the host builds
// (host/lib/prepare/bvh_build.cpp).
//
// Each node is eight rows of eight floats, one child per lane (structure of arrays, so that the
// eight box tests are one vector operation per step: one AVX instruction natively and in PoCL):
// lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, meta, flags; integers are stored as float bits. An inner
// child has flags 0 and meta = its node index. A leaf child has flags = 0x80000000 | its number of
// packets (below) and meta = its first packet; leaves are intersected straight from their parent,
// so a leaf costs no node fetch. An unused lane is an empty leaf (no packet) with a point box. Node
// 0 is the root. Of the inner children that the ray enters the nearest is visited next and the
// others are pushed far-first with their entry distance, so a popped node that lies beyond the
// closest hit found meanwhile is skipped without a fetch. The host keeps every path's pushes within
// ETK_BVH_STACK.
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
#define ETK_BVH_WIDTH 8   // children per node
#define ETK_BVH_NODE 16   // float4 per node: 8 rows of ETK_BVH_WIDTH floats
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

// Slab tests of a node's eight boxes against [0, tmax], lane-wise (one vector operation per step
// on both back ends): entry and exit distances. A lane is entered when tnear <= tfar * slack; the
// slack keeps rays that graze a flat box from missing it. Each axis reads only its near and far
// planes, rows chosen once per ray by the direction's signs (etk_box_rows): with a finite,
// non-zero inverse (etk_safe_inverse) and lo <= hi, (near - o) * inv <= (far - o) * inv in
// floats too, so these are the min and max of the two planes' distances bit for bit, without
// min/max operations per axis.
typedef struct {
    int nx, ny, nz; // rows of the near planes (0-2: lo, 3-5: hi)
    int fx, fy, fz; // and of the far planes
} EtkBoxRows;

ETK_FN EtkBoxRows etk_box_rows(float3 inv_dir) {
    EtkBoxRows b;
    b.nx = inv_dir.x >= 0.0f ? 0 : 3;
    b.ny = inv_dir.y >= 0.0f ? 1 : 4;
    b.nz = inv_dir.z >= 0.0f ? 2 : 5;
    b.fx = 3 - b.nx;
    b.fy = 5 - b.ny;
    b.fz = 7 - b.nz;
    return b;
}

ETK_FN void etk_box_hit8(ETK_GLOBAL const float* nd, EtkBoxRows b, float8 ox, float8 oy, float8 oz,
                         float8 ix, float8 iy, float8 iz, float8 tmax, float8* tnear,
                         float8* tfar) {
    float8 nx = (etk_row8(nd, b.nx) - ox) * ix, fx = (etk_row8(nd, b.fx) - ox) * ix;
    float8 ny = (etk_row8(nd, b.ny) - oy) * iy, fy = (etk_row8(nd, b.fy) - oy) * iy;
    float8 nz = (etk_row8(nd, b.nz) - oz) * iz, fz = (etk_row8(nd, b.fz) - oz) * iz;
    *tnear = ETK_MAXF(ETK_MAXF(nx, ny), ETK_MAXF(nz, etk_splat8(0.0f)));
    *tfar = ETK_MINF(ETK_MINF(fx, fy), ETK_MINF(fz, tmax)) * 1.000001f;
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
// wide seen from 1 unit lost most of its hits; the hit lane computes the distance it keeps). The
// edges' part does not depend on tmax: four lanes test both parts at once (etk_lanes: a mask per
// lane), and a lane taken after another lane's hit shortened tmax tests its range again alone.
#define ETK_TRIANGLE_EDGES(u, v, w, det, zero)                                                     \
    ((((u >= zero) & (v >= zero) & (w >= zero)) | ((u <= zero) & (v <= zero) & (w <= zero))) &     \
     (det != zero) & (det - det == zero))
#define ETK_TRIANGLE_RANGE(t, terr, tmax, zero) ((t + terr > zero) & (t - terr < tmax))

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

// One lane of a packet test whose edges' part passed: the hit is taken when closer than hit->t
// (so of two triangles at the same distance the one tested first keeps it). Its distance is the
// ray's to the triangle's plane, from the edges in the scene's coordinates (as Moller-Trumbore has
// it): the edge functions' t, from vertices relative to the ray's origin, loses the digits of the
// distance over the triangle's size (a triangle 1e-6 the size of its distance is placed ~10% off),
// which the sign tests tolerate but the closest hit's choice and the boxes' culling do not.
ETK_FORCE_INLINE_FN int etk_triangle_lane(ETK_GLOBAL const float4* pk, int lane, EtkShearedRay r,
                                          float v, float w, float det, float t0, float terr,
                                          float prim, EtkHit* hit) {
    if (!ETK_TRIANGLE_RANGE(t0, terr, hit->t * 2.0f, 0.0f))
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
    // The vertices relative to the origin, sheared: the ray is then the kz axis. Each axis's
    // rows from one pointer, the vertices at constant offsets from it: three registers across
    // the traversal, where an index per row took nine.
    ETK_GLOBAL const float4* px = pk + r.kx;
    ETK_GLOBAL const float4* py = pk + r.ky;
    ETK_GLOBAL const float4* pz = pk + r.kz;
    float4 az = pz[ETK_PACKET_V0] - oz, bz = pz[ETK_PACKET_V1] - oz, cz = pz[ETK_PACKET_V2] - oz;
    float4 ax = (px[ETK_PACKET_V0] - ox) - sx * az, ay = (py[ETK_PACKET_V0] - oy) - sy * az;
    float4 bx = (px[ETK_PACKET_V1] - ox) - sx * bz, by = (py[ETK_PACKET_V1] - oy) - sy * bz;
    float4 cx = (px[ETK_PACKET_V2] - ox) - sx * cz, cy = (py[ETK_PACKET_V2] - oy) - sy * cz;
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
    etk_lanes lu = etk_lanes_of(u), lv = etk_lanes_of(v), lw = etk_lanes_of(w),
              ld = etk_lanes_of(det), lt = etk_lanes_of(t), le = etk_lanes_of(terr);
    uint lanes = etk_lane_bits4(ETK_TRIANGLE_EDGES(lu, lv, lw, ld, zero) &
                                ETK_TRIANGLE_RANGE(lt, le, etk_lanes_splat(hit->t * 2.0f), zero));
    if (!lanes)
        return 0;
    float4 prim = pk[ETK_PACKET_PRIM];
    return ((lanes & 1u) &&
            etk_triangle_lane(pk, 0, r, v.x, w.x, det.x, t.x, terr.x, prim.x, hit) && any_hit) ||
           ((lanes & 2u) &&
            etk_triangle_lane(pk, 1, r, v.y, w.y, det.y, t.y, terr.y, prim.y, hit) && any_hit) ||
           ((lanes & 4u) &&
            etk_triangle_lane(pk, 2, r, v.z, w.z, det.z, t.z, terr.z, prim.z, hit) && any_hit) ||
           ((lanes & 8u) &&
            etk_triangle_lane(pk, 3, r, v.w, w.w, det.w, t.w, terr.w, prim.w, hit) && any_hit);
}

ETK_FN float3 etk_safe_inverse(float3 d) {
    float3 r;
    r.x = 1.0f / (fabs(d.x) > 1e-20f ? d.x : (d.x < 0.0f ? -1e-20f : 1e-20f));
    r.y = 1.0f / (fabs(d.y) > 1e-20f ? d.y : (d.y < 0.0f ? -1e-20f : 1e-20f));
    r.z = 1.0f / (fabs(d.z) > 1e-20f ? d.z : (d.z < 0.0f ? -1e-20f : 1e-20f));
    return r;
}

// Intersects the packets of a leaf; returns 1 when any_hit and one was hit. Inlined: as a call,
// GCC passes its vectors through memory (native traversal ~10% slower), and in PoCL every vector
// register is the callee's, so the traversal kept the ray's vectors on the stack and reloaded
// them at every node (PoCL 6-7% slower than inlined into the traversal's outer loop, below). The
// ray by value: by pointer, GCC's inlined code kept less of it in registers (native ~5% slower),
// and PoCL was no faster for the copy it saves.
ETK_FORCE_INLINE_FN int etk_leaf_hit(ETK_GLOBAL const float4* packets, int first, int count,
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
    while (j > base && stack_t[j - 1] < t) { // insertion: at most seven moves
        stack[j] = stack[j - 1];
        stack_t[j] = stack_t[j - 1];
        --j;
    }
    stack[j] = child;
    stack_t[j] = t;
    *sp = *sp + 1;
}

// The inner children entered (bit mask `inner` of the lanes, entry distances tn, child indices
// meta[lane]): pushes all but the nearest and returns it, the node to visit next (-1: none).
// One child, most nodes, is visited without touching the stack, by a branch per mask with the
// lane as a constant: a predicted branch then loads the next node before the box test is done,
// where a lane index computed from the mask would wait for the test. Of two, the far one is
// pushed (of equal distances the near one is the later lane, as the sorted pushes have it).
ETK_FORCE_INLINE_FN int etk_bvh_next(ETK_GLOBAL const float* meta, float8 tn, uint inner,
                                     int* stack, float* stack_t, int* sp) {
    switch (inner) { // the lane as a constant: see above
    case 0u:
        return -1;
    case 1u:
        return (int)as_uint(meta[0]);
    case 2u:
        return (int)as_uint(meta[1]);
    case 4u:
        return (int)as_uint(meta[2]);
    case 8u:
        return (int)as_uint(meta[3]);
    case 16u:
        return (int)as_uint(meta[4]);
    case 32u:
        return (int)as_uint(meta[5]);
    case 64u:
        return (int)as_uint(meta[6]);
    case 128u:
        return (int)as_uint(meta[7]);
    default:
        break;
    }
    int a = etk_lowest_bit(inner);
    uint rest = inner & (inner - 1u);
    if (!(rest & (rest - 1u))) {
        int b = etk_lowest_bit(rest);
        float ta = etk_lane8(tn, a), tb = etk_lane8(tn, b);
        int near_lane = ta < tb ? a : b;
        int j = *sp;
        if (j < ETK_BVH_STACK) { // always, for trees the host builds
            stack[j] = (int)as_uint(meta[a + b - near_lane]);
            stack_t[j] = ta < tb ? tb : ta;
            *sp = j + 1;
        }
        return (int)as_uint(meta[near_lane]);
    }
    int base = *sp;
    do {
        int i = etk_lowest_bit(inner);
        inner &= inner - 1u;
        etk_bvh_push((int)as_uint(meta[i]), etk_lane8(tn, i), stack, stack_t, base, sp);
    } while (inner);
    *sp = *sp - 1;
    return stack[*sp];
}

// How far the ray still looks: the closest hit so far, with slack (a box's entry distance and a
// triangle's t round differently, so a child entered at the hit's own distance stays in).
ETK_FORCE_INLINE_FN float etk_bvh_reach(const EtkHit* hit) {
    return hit->t * 1.0000005f;
}

// The tmax of a ray without an end (to the map). A float3 made from a float4 keeps the float4's w
// in its vector's fourth lane under clang (PoCL), and the direction's reciprocal below is one
// vector division: a direction whose w held this (a shadow ray's length once did) divides it into
// a denormal, whose microcode assist took a third of PoCL's shadow-ray traversal. Directions keep
// w = 0 (the lane's reciprocal is then 1e20, etk_safe_inverse's clamp).
#define ETK_RAY_UNBOUNDED 3.0e38f

// Closest hit with t in (0, tmax), or any hit when any_hit != 0. Returns whether it hit.
// A node's lanes are tested at once and its entered children taken from bit masks: first its
// leaves, in lane order, each while its entry distance is still within the closest hit (the
// order of one-by-one lanes, which decides exact ties); then its inner children, the nearest
// visited next without a trip through the stack.
ETK_CL_NOINLINE_FN int etk_bvh_traverse(ETK_GLOBAL const float4* nodes,
                                        ETK_GLOBAL const float4* packets, float3 org, float3 dir,
                                        float tmax, int any_hit, EtkHit* hit) {
    EtkHit h; // a local: the stack's floats cannot alias it, so its distance stays in a register
    h.t = tmax;
    h.prim = -1;
    h.b1 = h.b2 = 0.0f;
    float3 inv_dir = etk_safe_inverse(dir);
    // The triangle test's frame, made at the first leaf: most shadow and bounce rays under an
    // open sky reach none, and it costs a division and a few branches.
    EtkShearedRay sr;
    int sheared = 0;
    float8 ox = etk_splat8(org.x), oy = etk_splat8(org.y), oz = etk_splat8(org.z);
    float8 ix = etk_splat8(inv_dir.x), iy = etk_splat8(inv_dir.y), iz = etk_splat8(inv_dir.z);
    EtkBoxRows rows = etk_box_rows(inv_dir);
    int stack[ETK_BVH_STACK];
    float stack_t[ETK_BVH_STACK];
    int sp = 0;
    int node = 0; // the node to visit; -1: pop one
    // The closest hit's distance and reach, splatted: they change only where a leaf is hit.
    float8 t8 = etk_splat8(h.t), lim = etk_splat8(etk_bvh_reach(&h));
    for (;;) {
        // Down the tree until a node whose entered children include leaves: a loop of its own,
        // without the leaf test, so that PoCL's clang allocates its registers apart from the leaf
        // test's (one loop with the leaf test inlined spilled the loop's state; as a call, the
        // ray's vectors: PoCL 6-7% slower either way, native the same).
        ETK_GLOBAL const float* nd;
        float8 tn;
        uint enter, leaf, leaves;
        for (;;) {
            if (node < 0) {
                if (sp == 0)
                    break;
                --sp;
                if (!(stack_t[sp] <= etk_bvh_reach(&h)))
                    continue; // entered beyond the closest hit found since it was pushed
                node = stack[sp];
            }
            nd = (ETK_GLOBAL const float*)(nodes + ETK_BVH_NODE * node);
            float8 tf;
            etk_box_hit8(nd, rows, ox, oy, oz, ix, iy, iz, t8, &tn, &tf);
            // Entered: tnear <= tfar and within the ray's reach.
            enter = etk_le_bits8(tn, tf) & etk_le_bits8(tn, lim);
            leaf = etk_sign_bits8(etk_row8(nd, 7)); // flags: the sign bit marks a leaf
            leaves = enter & leaf;
            if (leaves)
                break;
            node = etk_bvh_next(nd + 6 * ETK_BVH_WIDTH, tn, enter & ~leaf, stack, stack_t, &sp);
        }
        if (node < 0) // the stack is empty
            break;
        ETK_GLOBAL const float* meta = nd + 6 * ETK_BVH_WIDTH; // lane i: meta[i]
        ETK_GLOBAL const float* flags = nd + 7 * ETK_BVH_WIDTH;
        if (!sheared) {
            sr = etk_sheared_ray(org, dir);
            sheared = 1;
        }
        do {
            int i = etk_lowest_bit(leaves);
            leaves &= leaves - 1u;
            if (etk_lane8(tn, i) <= etk_bvh_reach(&h) &&
                etk_leaf_hit(packets, (int)as_uint(meta[i]), (int)(as_uint(flags[i]) & 0x7fffffffu),
                             sr, any_hit, &h)) {
                *hit = h;
                return 1;
            }
        } while (leaves);
        t8 = etk_splat8(h.t);
        lim = etk_splat8(etk_bvh_reach(&h));
        enter &= etk_le_bits8(tn, lim);
        node = etk_bvh_next(meta, tn, enter & ~leaf, stack, stack_t, &sp);
    }
    *hit = h;
    return h.prim >= 0;
}

ETK_END

#endif
