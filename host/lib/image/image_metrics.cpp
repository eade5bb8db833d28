#include "image/image_metrics.h"

#include "util/error.h"

#include <cmath>

namespace et {
namespace {
std::string size_text(int w, int h) {
    return std::to_string(w) + "x" + std::to_string(h);
}
} // namespace

ImageErrors compare_images(const RgbImage& a, const RgbImage& b,
                           const std::vector<unsigned char>& mask) {
    if (a.width != b.width || a.height != b.height)
        throw Error("image sizes differ: " + size_text(a.width, a.height) + " vs " +
                    size_text(b.width, b.height));
    const size_t n = static_cast<size_t>(a.width) * a.height;
    if (!mask.empty() && mask.size() != n)
        throw Error("mask has " + std::to_string(mask.size()) + " pixels, the images " +
                    std::to_string(n));
    double se = 0.0, rel = 0.0, ref2 = 0.0, sa = 0.0, sb = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!mask.empty() && !mask[i])
            continue;
        ++count;
        for (int c = 0; c < 3; ++c) {
            const double x = a.rgb[3 * i + c], y = b.rgb[3 * i + c], d = x - y;
            se += d * d;
            rel += d * d / (y * y + kRelMseEpsilon);
            ref2 += y * y;
            sa += x;
            sb += y;
        }
    }
    ImageErrors e;
    e.pixels = count;
    if (count == 0)
        return e;
    const double values = 3.0 * count;
    e.rmse = std::sqrt(se / values);
    e.rel_mse = rel / values;
    e.l2 = ref2 > 0.0 ? std::sqrt(se / ref2) : (se > 0.0 ? INFINITY : 0.0);
    e.mean_a = sa / values;
    e.mean_b = sb / values;
    return e;
}

std::vector<unsigned char> read_mask(const std::string& path, int width, int height) {
    RgbImage m = read_rgb_image(path);
    if (m.width != width || m.height != height)
        throw Error(path + ": mask is " + size_text(m.width, m.height) + ", the images are " +
                    size_text(width, height));
    std::vector<unsigned char> out(static_cast<size_t>(width) * height);
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = m.rgb[3 * i] > 0.5f ? 1 : 0;
    return out;
}

} // namespace et
