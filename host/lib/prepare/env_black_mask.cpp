#include "prepare/env_black_mask.h"
#include "kernels/envmap.h"

namespace et {

EnvBlackMask env_black_mask(const RgbImage& image) {
    const int B = ETK_ENV_BLACK_BLOCK;
    const int bw = (image.width + B - 1) / B, bh = (image.height + B - 1) / B;
    EnvBlackMask m;
    if (bw < 1 || bh < 1)
        return m;
    // Blocks holding any non-zero channel.
    std::vector<char> lit(size_t(bw) * bh, 0);
    for (int y = 0; y < image.height; ++y) {
        const float* row = &image.rgb[size_t(y) * image.width * 3];
        for (int x = 0; x < image.width; ++x)
            if (row[3 * x] != 0.0f || row[3 * x + 1] != 0.0f || row[3 * x + 2] != 0.0f)
                lit[size_t(y / B) * bw + x / B] = 1;
    }
    std::vector<int> bits((size_t(bw) * bh + 31) / 32, 0);
    bool any = false;
    for (int by = 0; by < bh; ++by)
        for (int bx = 0; bx < bw; ++bx) {
            bool black = true;
            for (int dy = -1; dy <= 1 && black; ++dy) {
                const int y = by + dy;
                if (y < 0 || y >= bh)
                    continue; // past a pole: the lookup clamps to the block's own rows
                for (int dx = -1; dx <= 1 && black; ++dx)
                    black = !lit[size_t(y) * bw + (bx + dx + bw) % bw];
            }
            if (black) {
                const int bit = by * bw + bx;
                bits[bit / 32] |= 1 << (bit % 32);
                any = true;
            }
        }
    if (any) {
        m.width = bw;
        m.height = bh;
        m.bits = std::move(bits);
    }
    return m;
}

} // namespace et
