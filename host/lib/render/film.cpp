#include "render/film.h"

#include "util/error.h"

#include <string>

namespace et {

Film::Film(int width, int height) : width_(width), height_(height) {
#define ET_FILM_ZERO(type, name) name.assign(pixels(), type{});
    ETK_FILM_FIELDS(ET_FILM_ZERO)
#undef ET_FILM_ZERO
}

etk::EtkFilm Film::view() {
#define ET_FILM_DATA(type, name) name.data(),
    return etk::EtkFilm{ETK_FILM_FIELDS(ET_FILM_DATA)};
#undef ET_FILM_DATA
}

std::vector<float> Film::mean() const {
    std::vector<float> rgb(3 * pixels());
    for (size_t i = 0; i < pixels(); ++i) {
        const etk::float4 s = film_sum[i];
        const float inv = s.w > 0.0f ? 1.0f / s.w : 0.0f;
        rgb[3 * i] = s.x * inv;
        rgb[3 * i + 1] = s.y * inv;
        rgb[3 * i + 2] = s.z * inv;
    }
    return rgb;
}

std::vector<float> Film::variance_of_mean() const {
    std::vector<float> var(3 * pixels(), 0.0f);
    for (size_t i = 0; i < pixels(); ++i) {
        const double n = film_sum[i].w;
        if (n < 2.0)
            continue;
        const float* s = &film_sum[i].x;
        const float* q = &film_sq[i].x;
        for (int c = 0; c < 3; ++c) {
            const double m = s[c] / n;
            const double s2 = (q[c] - n * m * m) / (n - 1.0);
            var[3 * i + c] = static_cast<float>(s2 > 0.0 ? s2 / n : 0.0);
        }
    }
    return var;
}

void Film::add(const Film& o) {
    if (o.width_ != width_ || o.height_ != height_)
        throw Error("cannot add a " + std::to_string(o.width_) + "x" + std::to_string(o.height_) +
                    " film to a " + std::to_string(width_) + "x" + std::to_string(height_) +
                    " one");
    for (size_t i = 0; i < pixels(); ++i) {
#define ET_FILM_ADD(type, name)                                                                    \
    name[i] = etk::make_float4(name[i].x + o.name[i].x, name[i].y + o.name[i].y,                   \
                               name[i].z + o.name[i].z, name[i].w + o.name[i].w);
        ETK_FILM_FIELDS(ET_FILM_ADD)
#undef ET_FILM_ADD
    }
}

} // namespace et
