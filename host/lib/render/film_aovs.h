// The exact sums of the AOVs (kernels/aov.h): per pixel the albedo, shading normal and depth of
// each sample's first hit, and how many samples hit, added in the fixed point of the film's
// radiance sums (film_sums.h: units of 2^-70 in 128-bit integers), so that, like the image, they
// do not depend on how the sample indices were split over passes, processes, ranks or farm
// tasks. Kept by FilmSums only when the render asks for AOVs (`render --aovs`): 128 bytes per
// pixel beside the 112 of the radiance.
#pragma once
#include "kernels/compat.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace et {

__extension__ typedef __int128 int128;

struct alignas(16) AovPixel {
    enum { kAlbedo = 0, kNormal = 3, kDepth = 6, kValues = 7 };
    int128 sum[kValues];      // albedo RGB, normal XYZ, depth: sums over the samples
    uint32_t hits;            // samples whose camera ray hit a surface
    uint8_t special[kValues]; // FilmSums' flags per value (a depth of 2^56 or more, NaN)
    uint8_t pad[5];           // always 0 (files hold the raw bytes)
};
static_assert(sizeof(AovPixel) == 128, "AovPixel is written to files and MPI messages as bytes");

// Adds one pass's AOVs (film_albedo, film_normal of kernels/path_state.h) of `n` pixels.
void add_aov_pass(AovPixel* to, const etk::float4* albedo, const etk::float4* normal, size_t n);
// Adds `n` pixels of `from` to `to` (exactly; the MPI reduction's operator too).
void add_aov_pixels(AovPixel* to, const AovPixel* from, size_t n);

// The AOV images (row-major, row 0 at the top): albedo (RGB) and normal (XYZ) averaged over all
// samples of a pixel (misses count as zero: the alpha-free input a denoiser wants), depth
// averaged over the samples that hit, kNoHitDepth where none did (outputs hold no inf).
// FilmSums::aov_images makes them.
constexpr float kNoHitDepth = 1e10f;
struct AovImages {
    std::vector<float> albedo, normal, depth;
};

// Shared with film_sums.cpp: one float sample into a fixed-point sum (or its flag), and a sum's
// value with its flags (film_sums.h).
void film_accumulate(int128& acc, uint8_t& special, float v);
double film_channel_value(int128 acc, uint8_t special);

} // namespace et
