// Error metrics between a rendered image and a reference, as used by `envtrace compare` and the
// experiments (docs/history/results-journal.md defines each one).
#pragma once
#include "image/image_io.h"

#include <string>
#include <vector>

namespace et {

// Added to b^2 in the relative MSE so black reference pixels do not divide by zero.
constexpr double kRelMseEpsilon = 1e-2;

struct ImageErrors {
    size_t pixels = 0;    // pixels compared (inside the mask)
    double rmse = 0.0;    // sqrt(mean over pixels and channels of (a - b)^2)
    double rel_mse = 0.0; // mean over pixels and channels of (a - b)^2 / (b^2 + kRelMseEpsilon)
    double l2 = 0.0;      // relative L2 norm: sqrt(sum (a - b)^2) / sqrt(sum b^2)
    double mean_a = 0.0, mean_b = 0.0; // mean over pixels and channels
};

// Compares `a` against the reference `b` over the pixels where `mask` is non-zero (an empty mask
// selects every pixel). Throws et::Error on a size mismatch, naming both sizes.
ImageErrors compare_images(const RgbImage& a, const RgbImage& b,
                           const std::vector<unsigned char>& mask = {});

// Reads a mask image: a pixel is selected when its first channel is above 0.5 (linear).
std::vector<unsigned char> read_mask(const std::string& path, int width, int height);

} // namespace et
