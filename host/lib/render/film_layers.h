// The channels of a render's OpenEXR output, named as compositors (Nuke) and denoisers (Intel
// Open Image Denoise's inputs color/albedo/normal) read them:
//   R G B                        the image, the mean radiance
//   albedo.R albedo.G albedo.B   first hit's albedo, averaged over all samples (film_aovs.h)
//   N.X N.Y N.Z                  first hit's shading normal, world space, facing the camera
//   Z                            depth along the camera's axis, averaged over the samples
//                                that hit; kNoHitDepth (1e10) where none did
//   variance.R .G .B             the estimated variance of each channel of the pixel mean, s^2/n
// The last four groups only for a film with AOVs (`render --aovs`); channels in this order.
#pragma once
#include "render/film_sums.h"

#include <string>
#include <vector>

namespace et {

struct FilmLayers {
    std::vector<std::string> names; // channel names, in pixel order
    std::vector<float> pixels;      // interleaved: names.size() floats per pixel
};

FilmLayers film_layers(const FilmSums& sums);

} // namespace et
