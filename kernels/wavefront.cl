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

#define ETK_NAME(type, name) name,
#define ETK_QUEUE_NAME(name) name,
#define ETK_STAGE_KERNEL(name, fn)                                                                 \
    __kernel void name(ETK_KERNEL_ARGS) {                                                          \
        EtkScene S = {ETK_SCENE_BUFFERS(ETK_NAME)};                                                \
        EtkPaths P = {ETK_PATH_FIELDS(ETK_NAME)};                                                  \
        EtkQueues Q = {ETK_QUEUES(ETK_QUEUE_NAME) counters};                                       \
        EtkFilm F = {ETK_FILM_FIELDS(ETK_NAME)};                                                   \
        int i = get_global_id(0);                                                                  \
        if (i < n)                                                                                 \
            fn(S, P, Q, F, params, i);                                                             \
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
