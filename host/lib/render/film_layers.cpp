#include "render/film_layers.h"

namespace et {

FilmLayers film_layers(const FilmSums& sums) {
    FilmLayers out;
    out.names = {"R", "G", "B"};
    const std::vector<float> mean = sums.mean();
    if (!sums.has_aovs()) {
        out.pixels = mean;
        return out;
    }
    out.names.insert(out.names.end(), {"albedo.R", "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z", "Z",
                                       "variance.R", "variance.G", "variance.B"});
    const AovImages aov = sums.aov_images();
    const std::vector<float> var = sums.variance_of_mean();
    const size_t k = out.names.size(), n = sums.pixels();
    out.pixels.resize(k * n);
    for (size_t i = 0; i < n; ++i) {
        float* p = &out.pixels[k * i];
        for (int c = 0; c < 3; ++c) {
            p[c] = mean[3 * i + c];
            p[3 + c] = aov.albedo[3 * i + c];
            p[6 + c] = aov.normal[3 * i + c];
            p[10 + c] = var[3 * i + c];
        }
        p[9] = aov.depth[i];
    }
    return out;
}

} // namespace et
