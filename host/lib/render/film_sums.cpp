#include "render/film_sums.h"

#include "kernels/film_fixed.h"

#include "util/error.h"
#include "util/parallel.h"

#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <string>

namespace et {
namespace {

// The device's pixel (kernels/film_fixed.h) is this one, byte for byte: a GPU's sums are read
// straight into pixels_.
static_assert(sizeof(etk::EtkFixedPixel) == sizeof(FilmSums::Pixel), "film_fixed.h");
static_assert(offsetof(etk::EtkFixedPixel, sq) == offsetof(FilmSums::Pixel, sq), "film_fixed.h");
static_assert(offsetof(etk::EtkFixedPixel, count) == offsetof(FilmSums::Pixel, count),
              "film_fixed.h");
static_assert(offsetof(etk::EtkFixedPixel, special) == offsetof(FilmSums::Pixel, special),
              "film_fixed.h");
static_assert(FilmSums::kFractionBits == ETK_FILM_FRACTION_BITS &&
                  FilmSums::kPositiveOverflow == ETK_FILM_POSITIVE_OVERFLOW &&
                  FilmSums::kNegativeOverflow == ETK_FILM_NEGATIVE_OVERFLOW &&
                  FilmSums::kNaN == ETK_FILM_NAN,
              "film_fixed.h");

int128 from_words(etk::EtkFixed128 x) {
    return static_cast<int128>((static_cast<unsigned __int128>(x.hi) << 64) | x.lo);
}

inline double channel(int128 acc, uint8_t special) {
    return film_channel_value(acc, special);
}

} // namespace

// Adds one float sample to a channel: exact fixed point, or a flag when it cannot be held.
void film_accumulate(int128& acc, uint8_t& special, float v) {
    if (const uint8_t flag = static_cast<uint8_t>(etk::etk_fixed_special(v)))
        special |= flag;
    else
        acc += from_words(etk::etk_fixed_from_float(v));
}

// What a channel's value becomes: the finite sum, or inf/NaN as its flags say.
double film_channel_value(int128 acc, uint8_t special) {
    if (special == 0)
        return film_fixed_to_double(acc);
    if (special == FilmSums::kPositiveOverflow)
        return std::numeric_limits<double>::infinity();
    if (special == FilmSums::kNegativeOverflow)
        return -std::numeric_limits<double>::infinity();
    return std::numeric_limits<double>::quiet_NaN();
}

int128 film_fixed_point(float v) {
    return from_words(etk::etk_fixed_from_float(v));
}

double film_fixed_to_double(int128 x) {
    return std::ldexp(static_cast<double>(x), -FilmSums::kFractionBits);
}

FilmSums::FilmSums(int width, int height, bool aovs)
    : width_(width), height_(height),
      pixels_(static_cast<size_t>(width) * static_cast<size_t>(height), Pixel{}) {
    if (aovs)
        aovs_.assign(pixels_.size(), AovPixel{});
}

void FilmSums::add_pass(const Film& pass, int threads_wanted) {
    if (pass.width() != width_ || pass.height() != height_)
        throw Error("cannot add a " + std::to_string(pass.width()) + "x" +
                    std::to_string(pass.height()) + " pass to a " + std::to_string(width_) + "x" +
                    std::to_string(height_) + " film");
    // Every pass of a render is folded here, on the host, while the device waits: ~7 ms for
    // 512x512 on one core (a 112-byte sum per pixel read and written), 5% of a depth-1 pass.
    // Pixels are independent, so large films are split over the cores, which the renderer
    // leaves idle between passes: the same sums.
    const size_t n = pixels_.size();
    const int threads = n >= kParallelFoldPixels ? thread_count(threads_wanted) : 1;
    run_on_threads(threads, [&](int t) {
        const size_t begin = n * t / threads, end = n * (t + 1) / threads;
        for (size_t i = begin; i < end; ++i) {
            // The device's fold (kernels/film_fixed.h), on a copy: no aliasing of the int128s.
            etk::EtkFixedPixel p;
            std::memcpy(&p, &pixels_[i], sizeof p);
            etk::etk_fixed_add_pixel(&p, pass.film_sum[i], pass.film_sq[i]);
            std::memcpy(&pixels_[i], &p, sizeof p);
        }
        if (has_aovs())
            add_aov_pass(aovs_.data() + begin, pass.film_albedo.data() + begin,
                         pass.film_normal.data() + begin, end - begin);
    });
}

void FilmSums::add_pixels(Pixel* to, const Pixel* from, size_t n) {
    for (size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
            to[i].sum[c] += from[i].sum[c];
            to[i].sq[c] += from[i].sq[c];
        }
        for (int c = 0; c < 6; ++c)
            to[i].special[c] |= from[i].special[c];
        to[i].count += from[i].count;
    }
}

void FilmSums::add(const FilmSums& o) {
    if (o.width_ != width_ || o.height_ != height_)
        throw Error("cannot add a " + std::to_string(o.width_) + "x" + std::to_string(o.height_) +
                    " film to a " + std::to_string(width_) + "x" + std::to_string(height_) +
                    " one");
    if (o.has_aovs() != has_aovs())
        throw Error(std::string("cannot add a film ") + (o.has_aovs() ? "with" : "without") +
                    " AOVs to one " + (has_aovs() ? "with" : "without"));
    add_pixels(pixels_.data(), o.pixels_.data(), pixels_.size());
    add_aov_pixels(aovs_.data(), o.aovs_.data(), aovs_.size());
}

AovImages FilmSums::aov_images() const {
    AovImages im;
    if (!has_aovs())
        return im;
    const size_t n = pixels();
    im.albedo.assign(3 * n, 0.0f);
    im.normal.assign(3 * n, 0.0f);
    im.depth.assign(n, kNoHitDepth);
    for (size_t i = 0; i < n; ++i) {
        const AovPixel& a = aovs_[i];
        const double count = pixels_[i].count;
        if (count > 0)
            for (int c = 0; c < 3; ++c) {
                im.albedo[3 * i + c] = static_cast<float>(
                    channel(a.sum[AovPixel::kAlbedo + c], a.special[AovPixel::kAlbedo + c]) /
                    count);
                im.normal[3 * i + c] = static_cast<float>(
                    channel(a.sum[AovPixel::kNormal + c], a.special[AovPixel::kNormal + c]) /
                    count);
            }
        if (a.hits > 0)
            im.depth[i] = static_cast<float>(
                channel(a.sum[AovPixel::kDepth], a.special[AovPixel::kDepth]) / a.hits);
    }
    return im;
}

std::vector<float> FilmSums::mean() const {
    std::vector<float> rgb(3 * pixels());
    for (size_t i = 0; i < pixels(); ++i) {
        const Pixel& p = pixels_[i];
        for (int c = 0; c < 3; ++c)
            rgb[3 * i + c] =
                p.count > 0 ? static_cast<float>(channel(p.sum[c], p.special[c]) / p.count) : 0.0f;
    }
    return rgb;
}

std::vector<float> FilmSums::variance_of_mean() const {
    std::vector<float> var(3 * pixels(), 0.0f);
    for (size_t i = 0; i < pixels(); ++i) {
        const Pixel& p = pixels_[i];
        const double n = p.count;
        if (n < 2.0)
            continue;
        for (int c = 0; c < 3; ++c) {
            const double m = channel(p.sum[c], p.special[c]) / n;
            const double s2 = (channel(p.sq[c], p.special[3 + c]) - n * m * m) / (n - 1.0);
            var[3 * i + c] = static_cast<float>(s2 > 0.0 ? s2 / n : 0.0);
        }
    }
    return var;
}

bool FilmSums::operator==(const FilmSums& o) const {
    // memcmp of an empty vector's data() (nullptr) is undefined even for 0 bytes (UBSan).
    return width_ == o.width_ && height_ == o.height_ && pixels_.size() == o.pixels_.size() &&
           aovs_.size() == o.aovs_.size() &&
           (pixels_.empty() ||
            std::memcmp(pixels_.data(), o.pixels_.data(), pixels_.size() * sizeof(Pixel)) == 0) &&
           (aovs_.empty() ||
            std::memcmp(aovs_.data(), o.aovs_.data(), aovs_.size() * sizeof(AovPixel)) == 0);
}

} // namespace et
