// Display images: tone-mapped previews of linear radiance and the sample-point plot (Figure 6).
#pragma once
#include "image_io.h"

#include <vector>

namespace et {

// Linear RGB -> display RGB in [0,1]: exposure so the mean luminance maps to 0.18 (or the given
// exposure when > 0), a Reinhard curve on luminance, then sRGB encoding.
std::vector<float> tone_map(const RgbImage& img, float exposure = 0.0f);

// Draws a filled dot of `radius` pixels with a dark outline at lat-long coordinates (u, v) into a
// display image, wrapping horizontally.
void draw_dot(std::vector<float>& display, int width, int height, float u, float v, int radius,
              const float colour[3]);

} // namespace et
