// The wavefront's data, declared once. Every list below is an X-macro: the structs the stages
// take (EtkScene, EtkPaths, EtkQueues, EtkFilm), the OpenCL kernel argument list, the host's
// argument indices, buffer allocation, bytes per path, stage names and queue counters are all
// expanded from these lists, so adding a field is one line here (and what reads it).
#ifndef ETK_PATH_STATE_H
#define ETK_PATH_STATE_H
#include "compat.h"

// Scene buffers, read-only, one element type each: X(type, name).
#define ETK_SCENE_BUFFERS(X)                                                                       \
    X(float4, nodes)        /* BVH: 8-wide nodes (bvh.h) */                                        \
    X(float4, packets)      /* BVH: the leaves' triangles, four per packet (bvh.h) */              \
    X(float4, face_normals) /* geometric normal per triangle */                                    \
    X(int, packet_slot)     /* per triangle: its packet x 4 + lane (bvh.h), for its vertices */    \
    X(float4, normals)      /* three vertex normals per triangle */                                \
    X(int, tri_material)    /* material index per triangle */                                      \
    X(float4, materials)    /* two float4 per material (bsdf.h) */                                 \
    X(float, env_dist)      /* the map's 2D distribution (piecewise_constant.h) */                 \
    X(float, env_dist_comp) /* its MIS-compensated twin (ETK_LIGHT_COMPENSATED) */                 \
    X(float, env_texels)    /* the map's RGB texels */                                             \
    X(int, env_black)       /* bits: the map's blocks that are black for certain (envmap.h) */     \
    X(float4, lights)       /* directional lights / SIS strata: direction, power */                \
    X(int, strata_texels)   /* SIS: texels sorted by stratum */                                    \
    X(int, strata_begin)    /* SIS: stratum k owns strata_texels[begin[k] .. begin[k+1]) */        \
    X(float, strata_cdf)    /* SIS: running solid-angle fraction inside each stratum */            \
    X(int, material_tex)    /* textures of each material, ETK_TEX_SLOTS ints (texture_lookup.h) */ \
    X(float, tri_uv)        /* texture coordinates: (u, v) of 3 corners per triangle */            \
    X(float4, tex_info)     /* per texture: (offset, width, height, channels), uv transform */     \
    X(float, tex_texels)    /* every texture's texels, one flat array */                           \
    X(float, guide_regions) /* visibility: the map's mass and row tables per region */             \
    X(float, guide_cells)   /* visibility: per hash-grid cell, CDFs over regions (light sample;    \
                               continuation guide) */

// Path state, one element per path in flight: X(type, name).
#define ETK_PATH_FIELDS(X)                                                                         \
    X(float4, ray_o)     /* origin */                                                              \
    X(float4, ray_d)     /* direction */                                                           \
    X(int, depth)        /* surface interactions before the ray's origin */                        \
    X(float, ray_pdf)    /* density the ray was drawn from (BSDF or guided mixture); < 0 for a     \
                            camera ray or a delta sample */                                        \
    X(int, ray_cell)     /* the cell of the vertex that drew the ray: its light source's (binned,  \
                            learned; etk_light_source) */                                          \
    X(float4, beta)      /* throughput */                                                          \
    X(float4, radiance)  /* accumulated along the path */                                          \
    X(float, eta_scale)  /* its refractions' eta^2, which Russian roulette takes out of the        \
                            throughput it weighs (integrator.h) */                                 \
    X(float4, hit)       /* t, triangle (int bits), b1, b2 */                                      \
    X(float4, shadow_o)  /* shadow ray origin */                                                   \
    X(float4, shadow_d)  /* shadow ray direction (to the map: unbounded); w: 0 */                  \
    X(float4, shadow_L)  /* tentative contribution of the shadow ray */                            \
    X(int, shadow_key)   /* visibility learning: its cell x regions + region of its direction      \
                            (it and guide_parts written by sample_lights for learned samples) */   \
    X(float, shadow_val) /* visibility learning: its unweighted L cos / pdf */                     \
    X(int, pixel)        /* film pixel of the path */                                              \
    X(float2, guide_parts) /* visibility learning: the shadow ray's p_vis and p_portal */          \
    X(int, guide_noted) /* visibility learning: bit k: guided vertex k's record is noted below */  \
    X(EtkGuideVertices,                                                                            \
      guide_vertices)    /* its records until the path ends (visibility_record.h) */               \
    X(float4, light_dir) /* the light sample of the path's vertex, drawn by sample_lights:         \
                            direction; w: its density (integrator.h) */                            \
    X(float4, light_L)   /* its radiance (rgb) */                                                  \
    X(int, light_cell)   /* the cell sample_lights drew it in (etk_light_source) */

// Work queues of path slots, one int per path in flight: X(name). ray_in and ray_out swap
// buffers between bounces; the others keep one buffer each for the whole render (the back ends
// allocate them from ETK_FIXED_QUEUES). Escaped rays need no queue: intersect takes their light.
#define ETK_FIXED_QUEUES(X) X(shade) X(shadow)
#define ETK_QUEUES(X) X(ray_in) X(ray_out) ETK_FIXED_QUEUES(X)

// Film, one element per pixel: X(type, name).
#define ETK_FILM_FIELDS(X)                                                                         \
    X(float4, film_sum)    /* sum of samples (RGB); w: number of samples */                        \
    X(float4, film_sq)     /* sum of squared samples (RGB): the per-pixel variance */              \
    X(float4, film_albedo) /* first hit's albedo (RGB); w: 1 if the camera ray hit (aov.h) */      \
    X(float4, film_normal) /* first hit's shading normal (world); w: its depth (aov.h) */

// Queue counters, bumped atomically: X(name).
#define ETK_COUNTERS(X)                                                                            \
    X(RAY_OUT)    /* continuation rays pushed */                                                   \
    X(SHADOW)     /* shadow rays pushed */                                                         \
    X(SHADE)      /* rays that hit a surface to shade */                                           \
    X(LIGHT_RAYS) /* shadow rays traced inline by shade_lights */                                  \
    X(NONFINITE)  /* samples dropped by the film: should stay 0 */                                 \
    /* A wave counted on the device (etk_next_bounce): */                                          \
    X(RAY_IN)      /* the rays this bounce intersects */                                           \
    X(SUM_RAYS_IN) /* continuation rays of the bounces before it */                                \
    X(SUM_SHADE)   /* their surface hits shaded */                                                 \
    X(SUM_SHADOW)  /* their shadow rays, traced by trace_shadows or inline */

// The stages, in schedule order: X(kernel name, stage function, pushes). integrator.h defines the
// functions, all with one signature; the schedule (host/lib/render/schedule.cpp) runs them.
// pushes: 1 where the stage queues paths (EtkPushes below), which the OpenCL kernel then makes
// per work-group, behind barriers; a stage marked 0 that pushes is still correct, only slower.
#define ETK_STAGES(X)                                                                              \
    X(generate, etk_generate, 0)                                                                   \
    X(intersect, etk_intersect, 1)                                                                 \
    X(sample_lights, etk_sample_lights, 0)                                                         \
    X(shade_hits, etk_shade, 1)                                                                    \
    X(shade_lights, etk_shade_lights, 0)                                                           \
    X(trace_shadows, etk_shadow, 0)                                                                \
    X(accumulate, etk_accumulate, 0)

ETK_BEGIN

// The continuation records a learning path keeps until it ends: the first ETK_GUIDE_VERTICES
// guided vertices', ETK_GUIDE_VERTEX_FLOAT4S float4s each (kernels/visibility_record.h).
#define ETK_GUIDE_VERTICES 8
#define ETK_GUIDE_VERTEX_FLOAT4S 4
typedef struct {
    float4 v[ETK_GUIDE_VERTICES * ETK_GUIDE_VERTEX_FLOAT4S];
} EtkGuideVertices;

#define ETK_COUNTER_ENUM(name) ETK_Q_##name,
enum { ETK_COUNTERS(ETK_COUNTER_ENUM) ETK_Q_COUNT };
#undef ETK_COUNTER_ENUM

// A stage's queue pushes are collected in an EtkPushes and made after the stage function returns:
// natively one at a time (etk_push_each: the lane's own counters), on OpenCL with one global
// atomic per work-group and queue (wavefront.cl), since every work-item bumping the same global
// counter makes its cache line travel between cores on a CPU device (4% of a frame on
// PoCL). The pushing queues are those of the first ETK_PUSH_QUEUES counters.
#define ETK_PUSH_QUEUES 3
// The largest work-group the host launches stages with (wavefront.cl keeps a group's pushes in
// local arrays of this size).
#define ETK_STAGE_LOCAL_MAX 64
typedef struct {
    int slot[ETK_PUSH_QUEUES]; // by counter (ETK_Q_RAY_OUT ... ETK_Q_SHADE): the slot, or -1
} EtkPushes;
// EtkPushes indexes its slots by the first three counters.
typedef char etk_push_counters_come_first[((ETK_Q_RAY_OUT == 0) & (ETK_Q_SHADOW == 1) &
                                           (ETK_Q_SHADE == 2) & (ETK_PUSH_QUEUES == 3))
                                              ? 1
                                              : -1];

// Path fields by name, for the host's reads of them (StageExecutor::read_fields).
#define ETK_FIELD_ENUM(type, name) ETK_FIELD_##name,
enum { ETK_PATH_FIELDS(ETK_FIELD_ENUM) ETK_FIELD_COUNT };
#undef ETK_FIELD_ENUM

#define ETK_STAGE_ENUM(kernel, fn, pushes) ETK_STAGE_##kernel,
enum { ETK_STAGES(ETK_STAGE_ENUM) ETK_STAGE_COUNT };
#undef ETK_STAGE_ENUM

#define ETK_CONST_MEMBER(type, name) ETK_GLOBAL const type* name;
#define ETK_MEMBER(type, name) ETK_GLOBAL type* name;
#define ETK_QUEUE_MEMBER(name) ETK_GLOBAL int* name;
typedef struct {
    ETK_SCENE_BUFFERS(ETK_CONST_MEMBER)
} EtkScene;
typedef struct {
    ETK_PATH_FIELDS(ETK_MEMBER)
} EtkPaths;
// The queues and the device's sums: the queue counters, and the visibility strategy's record sums
// (kernels/visibility_record.h; one word where nothing learns).
typedef struct {
    ETK_QUEUES(ETK_QUEUE_MEMBER)
    ETK_COUNTER_PTR counters;
    ETK_ATOMIC_PTR guide_sums;
} EtkQueues;
typedef struct {
    ETK_FILM_FIELDS(ETK_MEMBER)
} EtkFilm;
#undef ETK_CONST_MEMBER
#undef ETK_MEMBER
#undef ETK_QUEUE_MEMBER

// The light sample sample_lights drew for the path in `slot` (integrator.h): direction, density
// (0: none), radiance (0 where there is no sample) and the cell of its table (etk_light_cell's).
ETK_FN void etk_put_light_sample(EtkPaths P, int slot, float dx, float dy, float dz, float pdf,
                                 float r, float g, float b, int cell) {
    int lit = pdf > 0.0f;
    P.light_dir[slot] = make_float4(dx, dy, dz, pdf);
    P.light_L[slot] = make_float4(lit ? r : 0.0f, lit ? g : 0.0f, lit ? b : 0.0f, 0.0f);
    P.light_cell[slot] = cell;
}

ETK_FN EtkPushes etk_no_pushes(void) {
    EtkPushes out;
    for (int q = 0; q < ETK_PUSH_QUEUES; ++q)
        out.slot[q] = -1;
    return out;
}
// Queue of counter q (q < ETK_PUSH_QUEUES).
ETK_FN ETK_GLOBAL int* etk_push_queue(EtkQueues Q, int q) {
    return q == ETK_Q_RAY_OUT ? Q.ray_out : q == ETK_Q_SHADOW ? Q.shadow : Q.shade;
}
// The pushes, one atomic each, in counter order.
ETK_FN void etk_push_each(EtkQueues Q, const EtkPushes* out) {
    for (int q = 0; q < ETK_PUSH_QUEUES; ++q)
        if (out->slot[q] >= 0)
            etk_push_queue(Q, q)[ETK_COUNTER_INC(Q.counters + q)] = out->slot[q];
}

// Kernel arguments, in this order: scene buffers, path fields, queues, film, counters, guide sums,
// params, the queue length. ETK_KERNEL_ARGS (wavefront.cl) and EtkKernelArg (the host) both expand
// it.
#define ETK_ARG_INDEX(type, name) ETK_ARG_##name,
#define ETK_QUEUE_ARG_INDEX(name) ETK_ARG_##name,
enum {
    ETK_SCENE_BUFFERS(ETK_ARG_INDEX) ETK_PATH_FIELDS(ETK_ARG_INDEX) ETK_QUEUES(ETK_QUEUE_ARG_INDEX)
        ETK_FILM_FIELDS(ETK_ARG_INDEX) ETK_ARG_counters,
    ETK_ARG_guide_sums,
    ETK_ARG_params,
    ETK_ARG_n,
    ETK_ARG_COUNT
};
#undef ETK_ARG_INDEX
#undef ETK_QUEUE_ARG_INDEX

ETK_END

#endif
