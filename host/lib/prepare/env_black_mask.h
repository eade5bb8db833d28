// Which blocks of the map are black for certain (kernels/envmap.h, etk_env_black_uv): the last
// bounce's continuation is not traced towards them, since it could bring no light back. Maps whose
// light sits in a few texels on black (studio lamps, spot1Lux) skip most of those rays; a map with
// no black block gets no mask and the kernels never ask.
#pragma once
#include "image/image_io.h"

#include <cmath>
#include <vector>

namespace et {

struct EnvBlackMask {
    int width = 0, height = 0; // in blocks of ETK_ENV_BLACK_BLOCK texels; 0 x 0: no black block
    std::vector<int> bits;     // bit by * width + bx of word (by * width + bx) / 32
    // The solid angle (sr) of the blocks whose bit is clear: where any light can come from. 4 pi
    // without a mask. The compensated strategy's last bounce bounds the chance that a BSDF sample
    // finds light by it (kernels/integrator.h, etk_last_bsdf_share).
    float lit_solid_angle = static_cast<float>(4.0 * M_PI);
};

// A block's bit is set when its texels and those of its eight neighbours (wrapping in longitude,
// not past the poles) are zero in every channel: the bilinear lookup at any point of the block
// reads texels within one texel of it, so it reads zeros.
EnvBlackMask env_black_mask(const RgbImage& image);

} // namespace et
