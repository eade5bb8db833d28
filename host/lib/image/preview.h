// Display images: tone-mapped previews of linear radiance and the sample-point plot (Figure 6).
#pragma once
#include "image/image_io.h"

#include <array>
#include <string>
#include <vector>

namespace et {

// Linear RGB -> display RGB in [0,1]: exposure so the mean luminance maps to 0.18 (or the given
// exposure when > 0), a Reinhard curve on luminance, then sRGB encoding.
std::vector<float> tone_map(const RgbImage& img, float exposure = 0.0f);

// Draws a filled dot of `radius` pixels with a dark outline at lat-long coordinates (u, v) into a
// display image, wrapping horizontally.
void draw_dot(std::vector<float>& display, int width, int height, float u, float v, int radius,
              const float colour[3]);

// The map tone-mapped with a dot at each world-space direction (turned into map space by the
// map's rotation), written to `path`: the paper's Figure 6 for samples, Figure 8 for lights.
struct EnvMap;
class OutputBatch;
void write_direction_plot(OutputBatch& batch, const std::string& path, const EnvMap& env,
                          const std::vector<std::array<float, 3>>& directions);

} // namespace et
