// Denoising a rendered image with Intel Open Image Denoise 2 (its "RT" filter), guided by the
// first hit's albedo and normal (render/film_aovs.h), loaded at run time (oidn_library.h).
#pragma once
#include "image/image_io.h"

#include <string>

namespace et {

struct DenoiseOptions {
    // The beauty is linear radiance of any range (false: display values in [0, 1]).
    bool hdr = true;
    // Denoise the albedo and normal first, each with its own filter, and then the beauty with
    // cleanAux: OIDN's recommended path when the guides are themselves noisy (averaged over the
    // samples of a pixel, as a path tracer's are: depth of field, glossy or thin geometry).
    bool prefilter_guides = true;
};

// The denoised beauty. All three images are row-major RGB floats (RgbImage) of one size; the
// normal holds XYZ in [-1, 1] (any space; zero where nothing was hit). `albedo` and `normal` may
// be empty (width 0): the beauty alone, or beauty and albedo; a normal needs an albedo (OIDN's
// rule). Non-finite beauty values are denoised as 0. Throws et::Error for mismatched sizes, when
// the library is missing (oidn_library.h: the message says how to install it) or when it fails.
RgbImage denoise(const RgbImage& beauty, const RgbImage& albedo, const RgbImage& normal,
                 const DenoiseOptions& options = {});

// Loads the library and starts a device, so that a command fails before it spends time on a
// render whose output it could not denoise; throws denoise()'s error where that fails. Returns
// what was loaded, for reports: "Open Image Denoise 2.5.1 (FILE)".
std::string check_denoiser();

} // namespace et
