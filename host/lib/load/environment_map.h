// An environment map ready to render with: sanitised texels, its sampling distribution and the
// descriptor the kernels take. Lat-long convention: kernels/latlong.h.
#pragma once
#include "load/env_distribution.h"
#include "image/image_io.h"
#include "kernels/envmap.h"

#include <string>

namespace et {

// The brightest radiance a texel (times the intensity) may have: far below FLT_MAX, so that
// radiance x throughput x pdf ratios, summed over 2^24 samples, stay finite. Brighter texels are
// clamped with a warning (the physical sun is about 1.6e9).
constexpr float kMaxRadiance = 1e12f;

struct EnvMap {
    std::string name;
    RgbImage image;
    EnvDistribution dist;
    float scale = 1.0f;
    float rotation_degrees = 0.0f; // about the up (+Y) axis
    float max_texel = 0.0f;        // the largest channel value of `image`
    // load_envmap: seconds until the texels were decoded and sanitised, and the distribution's
    // thread time over the threads that built it (it overlaps the decoding).
    double load_seconds = 0.0, build_seconds = 0.0;

    etk::EtkEnvMap desc() const;
};

// Replaces non-finite values and negative channels by zero, so they neither light the scene nor
// poison the distribution, and clamps channels above kMaxRadiance; returns the number of texels
// changed and the largest channel left.
struct SanitizeReport {
    size_t non_finite = 0, negative = 0, too_bright = 0;
    float max_value = 0.0f;
};
SanitizeReport sanitize_texels(RgbImage& image);

// Reads the map (warning once about texels it had to zero, and about a non-2:1 aspect) and
// builds its distribution, on options.threads threads: the distribution's rows are built while
// the map's later rows are still decoding. The result does not depend on the thread count.
EnvMap load_envmap(const std::string& path, const DistributionOptions& options);

// Wraps an in-memory image (e.g. the procedural sky) the same way.
EnvMap make_envmap(std::string name, RgbImage image, const DistributionOptions& options);

// Clamps env.scale so that scale x max_texel <= kMaxRadiance, warning (naming `where`) if it had
// to.
void bound_intensity(EnvMap& env, const std::string& where);

// Parses "512x256" into a distribution resolution; throws et::Error on anything else.
void parse_resolution(const std::string& text, int& width, int& height);

} // namespace et
