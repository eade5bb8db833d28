// The film on the host: per-pixel sums of the samples and of their squares (the layout of
// kernels/film_accumulate.h, where the stages add to it). From them: the image (the mean), each
// pixel's variance, and the sum of two films (renders of disjoint sample ranges).
#pragma once
#include "kernels/path_state.h"

#include <cstddef>
#include <vector>

namespace et {

using etk::EtkGuideVertices;
using etk::float2;
using etk::float4;

// Film fields (by kernel argument, etk::ETK_ARG_film_*) that only a render keeping AOVs reads
// (kernels/aov.h): a pass neither zeroes nor hands them back otherwise.
constexpr bool film_field_is_aov(int arg) {
    return arg == etk::ETK_ARG_film_albedo || arg == etk::ETK_ARG_film_normal;
}

class Film {
  public:
    Film() = default;
    Film(int width, int height);

#define ET_FILM_VECTOR(type, name) std::vector<type> name;
    ETK_FILM_FIELDS(ET_FILM_VECTOR)
#undef ET_FILM_VECTOR

    int width() const {
        return width_;
    }
    int height() const {
        return height_;
    }
    size_t pixels() const {
        return static_cast<size_t>(width_) * height_;
    }
    etk::EtkFilm view();

    // Mean radiance per pixel (RGB, row-major, row 0 at the top); 0 where a pixel has no sample.
    std::vector<float> mean() const;
    // Per pixel and channel, the estimated variance of the mean, s^2 / n (0 below 2 samples).
    std::vector<float> variance_of_mean() const;
    // Adds another film of the same size (throws et::Error otherwise).
    void add(const Film& other);

  private:
    int width_ = 0, height_ = 0;
};

} // namespace et
