// The wavefront path tracer: one kernel per stage, generated from the stage list (ETK_STAGES in
// path_state.h; integrator.h holds the stages, shared with the native back end). Every kernel
// takes the same argument list, expanded from the same declarations, so the host sets it once;
// each runs over exactly the live entries of its queue (global size rounded up to the
// work-group size, the tail returning at once): n of them, or, where n < 0 (a wave counted on
// the device), as many as the queue's counter holds (etk_counted_items).
#include "film_fixed.h"
#include "integrator.h"

#define ETK_ARG_CONST(type, name) __global const type *name,
#define ETK_ARG(type, name) __global type *name,
#define ETK_ARG_QUEUE(name) __global int *name,
#define ETK_KERNEL_ARGS                                                                            \
    ETK_SCENE_BUFFERS(ETK_ARG_CONST)                                                               \
    ETK_PATH_FIELDS(ETK_ARG)                                                                       \
    ETK_QUEUES(ETK_ARG_QUEUE)                                                                      \
    ETK_FILM_FIELDS(ETK_ARG)                                                                       \
    volatile __global uint *counters, volatile __global uint *guide_sums, EtkParams params, int n

// The pushes of a work-group's stage calls (path_state.h): each work-item leaves its slots in
// local memory; after one barrier, work-item 0 reserves the group's run of each queue with one
// global atomic and writes the slots there in work-item order. One barrier and no local atomics:
// on a CPU device each barrier splits the kernel into loops over the group with the live state
// saved between them (PoCL); the local atomics and the three barriers of the earlier
// count-then-write scheme cost ~20% of the intersect stage there; the 64 x 3 slots
// are a short serial loop (on a GPU, one lane's loop over local memory). Every work-item calls
// this (the barrier), pushing or not.
static inline __attribute__((always_inline)) void etk_push_group(EtkQueues Q, EtkPushes out,
                                                                 __local int* slots) {
    int lid = get_local_id(0), lsize = get_local_size(0);
    for (int q = 0; q < ETK_PUSH_QUEUES; ++q)
        slots[q * ETK_STAGE_LOCAL_MAX + lid] = out.slot[q];
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid != 0)
        return;
    for (int q = 0; q < ETK_PUSH_QUEUES; ++q) {
        __local const int* s = slots + q * ETK_STAGE_LOCAL_MAX;
        uint count = 0u;
        for (int k = 0; k < lsize; ++k)
            count += s[k] >= 0 ? 1u : 0u;
        if (count == 0u)
            continue;
        __global int* queue = etk_push_queue(Q, q) + atomic_add(Q.counters + q, count);
        for (int k = 0; k < lsize; ++k)
            if (s[k] >= 0)
                *queue++ = s[k];
    }
}

#define ETK_NAME(type, name) name,
#define ETK_QUEUE_NAME(name) name,
#define ETK_STAGE_KERNEL(name, fn, pushes)                                                         \
    __kernel void name(ETK_KERNEL_ARGS) {                                                          \
        EtkScene S = {ETK_SCENE_BUFFERS(ETK_NAME)};                                                \
        EtkPaths P = {ETK_PATH_FIELDS(ETK_NAME)};                                                  \
        EtkQueues Q = {ETK_QUEUES(ETK_QUEUE_NAME) counters, guide_sums};                           \
        EtkFilm F = {ETK_FILM_FIELDS(ETK_NAME)};                                                   \
        __local int push_slots[ETK_PUSH_QUEUES * ETK_STAGE_LOCAL_MAX];                             \
        EtkPushes out = etk_no_pushes();                                                           \
        int i = get_global_id(0);                                                                  \
        int items = n >= 0 ? n : etk_counted_items(counters, ETK_STAGE_##name);                    \
        if ((int)(get_group_id(0) * get_local_size(0)) >= items)                                   \
            return; /* the whole group past the queue (so none of it reaches the barrier) */       \
        if (i < items)                                                                             \
            fn(S, P, Q, F, params, i, &out);                                                       \
        if (pushes) /* the others skip the group's barriers */                                     \
            etk_push_group(Q, out, push_slots);                                                    \
        else                                                                                       \
            etk_push_each(Q, &out);                                                                \
    }

ETK_STAGES(ETK_STAGE_KERNEL)

// Zeroes n 32-bit words: the queue counters before each bounce and the film before the first
// pass. A kernel rather than clEnqueueFillBuffer, so that the zeroes are written by the device
// like every other value (Oclgrind's uninitialised-value check does not count a fill).
__kernel void zero_words(__global uint* words, int n) {
    int i = get_global_id(0);
    if (i < n)
        words[i] = 0u;
}

// Between two bounces of a wave counted on the device (etk_next_bounce): one work-item.
__kernel void next_bounce(volatile __global uint* counters, int first_rays) {
    if (get_global_id(0) == 0)
        etk_next_bounce(counters, first_rays);
}

// Adds the pass's film (one sample per pixel, or none) to the render's exact sums on the device
// (film_fixed.h), n pixels: on a GPU the pass's film then never crosses the bus (ClDevice).
__kernel void fold_film(__global const float4* film_sum, __global const float4* film_sq,
                        __global EtkFixedPixel* sums, int n) {
    int i = get_global_id(0);
    if (i < n)
        etk_fixed_add_pixel(sums + i, film_sum[i], film_sq[i]);
}
