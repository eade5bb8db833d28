#include "render/film_sums.h"

#include "util/error.h"
#include "util/parallel.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace et {
namespace {

constexpr float kLimit = 72057594037927936.0f; // 2^56

inline void add_sample(int128& acc, uint8_t& special, float v) {
    film_accumulate(acc, special, v);
}
inline double channel(int128 acc, uint8_t special) {
    return film_channel_value(acc, special);
}

} // namespace

// Adds one float sample to a channel: exact fixed point, or a flag when it cannot be held.
void film_accumulate(int128& acc, uint8_t& special, float v) {
    if (std::isnan(v)) {
        special |= FilmSums::kNaN;
    } else if (!(std::fabs(v) < kLimit)) {
        special |= v > 0 ? FilmSums::kPositiveOverflow : FilmSums::kNegativeOverflow;
    } else {
        acc += film_fixed_point(v);
    }
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
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    const bool negative = bits >> 31;
    const int exponent = static_cast<int>((bits >> 23) & 0xffu);
    uint32_t mantissa = bits & 0x7fffffu;
    int e; // v = mantissa * 2^e
    if (exponent == 0) {
        e = -149; // subnormal
    } else {
        mantissa |= 0x800000u;
        e = exponent - 150;
    }
    const int shift = e + FilmSums::kFractionBits;
    int128 magnitude;
    if (shift >= 0)
        magnitude = static_cast<int128>(mantissa) << shift; // < 2^24 * 2^102 = 2^126 for |v| < 2^56
    else if (shift > -25)
        magnitude = (static_cast<uint64_t>(mantissa) + (uint64_t(1) << (-shift - 1))) >> -shift;
    else
        magnitude = 0; // below half a unit
    return negative ? -magnitude : magnitude;
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
            Pixel& p = pixels_[i];
            const etk::float4 s = pass.film_sum[i], q = pass.film_sq[i];
            add_sample(p.sum[0], p.special[0], s.x);
            add_sample(p.sum[1], p.special[1], s.y);
            add_sample(p.sum[2], p.special[2], s.z);
            add_sample(p.sq[0], p.special[3], q.x);
            add_sample(p.sq[1], p.special[4], q.y);
            add_sample(p.sq[2], p.special[5], q.z);
            p.count += static_cast<uint32_t>(s.w);
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
