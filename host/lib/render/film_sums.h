// The film's sums in exact arithmetic, so that they do not depend on the order of the samples:
// the renderer adds each pass (one float sample per pixel, kernels/film_accumulate.h) here,
// converted to fixed point (kernels/film_fixed.h, which a GPU runs on its own copy of these
// sums: ClDevice::fold_film), and two films of disjoint sample sets add exactly. A render split
// over MPI ranks or farm tasks (--sample-range, `envtrace merge`) therefore gives the bit-identical
// image of one process: integer addition is associative, float addition is not.
//
// Per pixel and channel (RGB of the sum, RGB of the sum of squares): a 128-bit integer counting
// units of 2^-70 (samples are rounded to that grid, a relative change below 2^-24 for any value
// above 2^-46 ~ 1.4e-14; smaller ones are below what a float film could hold next to a normal
// sample anyway). A sample of magnitude 2^56 (7.2e16) or more, or not finite, is not added but
// flagged, and the channel's mean becomes +inf, -inf or NaN as a float sum would have. A sum
// holds magnitudes below 2^57 (1.4e17): 2^24 samples (the most --spp allows) of up to 2^33 (8.6e9)
// each, or about 1,400 squares of a 1e7 firefly in the sum of squares. Past that it wraps, as
// it does in every process alike (merges stay bit-identical), and the pixel is wrong: a known
// limit, far above the radiance of the maps measured (a sun of ~1e5 squares to 1e10).
#pragma once
#include "render/film.h"
#include "render/film_aovs.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace et {

class FilmSums {
  public:
    static constexpr int kFractionBits = 70;
    enum : uint8_t { kPositiveOverflow = 1, kNegativeOverflow = 2, kNaN = 4 };
    struct alignas(16) Pixel {
        int128 sum[3];      // sum of the samples, RGB
        int128 sq[3];       // sum of their squares (each squared in float, as the device does)
        uint32_t count;     // samples added
        uint8_t special[6]; // kPositiveOverflow | kNegativeOverflow | kNaN per channel above
        uint8_t pad[6];     // always 0 (files hold the raw bytes)
    };
    static_assert(sizeof(Pixel) == 112, "Pixel is written to files and MPI messages as bytes");

    FilmSums() = default;
    // `aovs`: also keep the sums of the first hits' AOVs (film_aovs.h).
    FilmSums(int width, int height, bool aovs = false);

    int width() const { return width_; }
    int height() const { return height_; }
    size_t pixels() const { return pixels_.size(); }
    Pixel* data() { return pixels_.data(); }
    const Pixel* data() const { return pixels_.data(); }
    bool has_aovs() const { return !aovs_.empty(); }
    AovPixel* aov_data() { return aovs_.data(); }
    const AovPixel* aov_data() const { return aovs_.data(); }

    // Adds one pass: `pass` holds, per pixel, at most one sample (w = 1) or none (w = 0).
    // Films of several samples add too, but then their float sums were rounded already.
    // Films of kParallelFoldPixels or more are split over `threads` (0: every core).
    void add_pass(const Film& pass, int threads = 1);
    static constexpr size_t kParallelFoldPixels = 65536;
    // Adds the sums of a disjoint sample set, exactly (throws et::Error for another size, or
    // when one holds AOVs and the other not).
    void add(const FilmSums& other);
    // Adds `n` pixels of `from` to `to` (the MPI reduction's operator).
    static void add_pixels(Pixel* to, const Pixel* from, size_t n);

    // Mean radiance per pixel (RGB, row-major, row 0 at the top); 0 where a pixel has no sample.
    std::vector<float> mean() const;
    // Per pixel and channel, the estimated variance of the mean, s^2 / n (0 below 2 samples).
    std::vector<float> variance_of_mean() const;
    // The AOV images (empty without AOVs).
    AovImages aov_images() const;
    // Bitwise equality of every sum, count and flag.
    bool operator==(const FilmSums& o) const;

  private:
    int width_ = 0, height_ = 0;
    std::vector<Pixel> pixels_;
    std::vector<AovPixel> aovs_; // empty: no AOVs
};

// The fixed-point value of a float sample (finite, |v| < 2^56), rounded to the nearest unit of
// 2^-70 (ties away from zero). Exposed for the tests.
int128 film_fixed_point(float v);
// A fixed-point sum as a double (rounded to nearest).
double film_fixed_to_double(int128 x);

} // namespace et
