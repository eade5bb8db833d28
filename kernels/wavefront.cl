// The wavefront path tracer: one kernel per stage, generated from the stage list (ETK_STAGES in
// path_state.h; integrator.h holds the stages, shared with the native back end). Every kernel
// takes the same argument list, expanded from the same declarations, so the host sets it once;
// each runs over exactly the live entries of its queue (global size rounded up to the
// work-group size, the tail returning at once).
#include "integrator.h"

#define ETK_ARG_CONST(type, name) __global const type *name,
#define ETK_ARG(type, name) __global type *name,
#define ETK_ARG_QUEUE(name) __global int *name,
#define ETK_KERNEL_ARGS                                                                            \
    ETK_SCENE_BUFFERS(ETK_ARG_CONST)                                                               \
    ETK_PATH_FIELDS(ETK_ARG)                                                                       \
    ETK_QUEUES(ETK_ARG_QUEUE)                                                                      \
    ETK_FILM_FIELDS(ETK_ARG) volatile __global uint *counters, EtkParams params, int n

// The pushes of a work-group's stage calls (path_state.h): counted per queue in local memory,
// one global atomic per queue reserves the group's run, then each work-item writes its slot
// there. Every work-item calls this (barriers), pushing or not.
static inline __attribute__((always_inline)) void
etk_push_group(EtkQueues Q, EtkPushes out, __local uint* count, __local uint* base) {
    int lid = get_local_id(0), lsize = get_local_size(0);
    for (int q = lid; q < ETK_PUSH_QUEUES; q += lsize)
        count[q] = 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    uint mine[ETK_PUSH_QUEUES];
    for (int q = 0; q < ETK_PUSH_QUEUES; ++q)
        mine[q] = out.slot[q] >= 0 ? atomic_inc(count + q) : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int q = lid; q < ETK_PUSH_QUEUES; q += lsize)
        base[q] = count[q] > 0u ? atomic_add(Q.counters + q, count[q]) : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int q = 0; q < ETK_PUSH_QUEUES; ++q)
        if (out.slot[q] >= 0)
            etk_push_queue(Q, q)[base[q] + mine[q]] = out.slot[q];
}

#define ETK_NAME(type, name) name,
#define ETK_QUEUE_NAME(name) name,
#define ETK_STAGE_KERNEL(name, fn, pushes)                                                         \
    __kernel void name(ETK_KERNEL_ARGS) {                                                          \
        EtkScene S = {ETK_SCENE_BUFFERS(ETK_NAME)};                                                \
        EtkPaths P = {ETK_PATH_FIELDS(ETK_NAME)};                                                  \
        EtkQueues Q = {ETK_QUEUES(ETK_QUEUE_NAME) counters};                                       \
        EtkFilm F = {ETK_FILM_FIELDS(ETK_NAME)};                                                   \
        __local uint push_count[ETK_PUSH_QUEUES], push_base[ETK_PUSH_QUEUES];                      \
        EtkPushes out = etk_no_pushes();                                                           \
        int i = get_global_id(0);                                                                  \
        if (i < n)                                                                                 \
            fn(S, P, Q, F, params, i, &out);                                                       \
        if (pushes) /* the others skip the group's barriers */                                     \
            etk_push_group(Q, out, push_count, push_base);                                         \
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
