// The film on the device: per pixel, the sum of the samples (w counts them) and the sum of their
// squares. Enough to form the mean, to estimate each pixel's variance, to save and resume a
// render, and to add two films. The host side is host/lib/render/film.h. The first hit's AOVs
// (film_albedo, film_normal) are written by aov.h.
#ifndef ETK_FILM_ACCUMULATE_H
#define ETK_FILM_ACCUMULATE_H
#include "compat.h"
#include "path_state.h"

ETK_BEGIN

// Adds one sample of `pixel`. One path per pixel per pass: no atomics needed.
ETK_FN void etk_film_add(EtkFilm F, int pixel, float3 L) {
    float4 s = F.film_sum[pixel], q = F.film_sq[pixel];
    F.film_sum[pixel] = make_float4(s.x + L.x, s.y + L.y, s.z + L.z, s.w + 1.0f);
    F.film_sq[pixel] = make_float4(q.x + L.x * L.x, q.y + L.y * L.y, q.z + L.z * L.z, 0.0f);
}

ETK_END

#endif
