// An environment map ready to render with: sanitised texels, its sampling distribution and the
// descriptor the kernels take. Lat-long convention: kernels/latlong.h.
#pragma once
#include "load/env_distribution.h"
#include "image/image_io.h"
#include "kernels/envmap.h"

#include <string>

namespace et {

struct EnvMap {
    std::string name;
    RgbImage image;
    EnvDistribution dist;
    float scale = 1.0f;
    float rotation_degrees = 0.0f; // about the up (+Y) axis
    double load_seconds = 0.0, build_seconds = 0.0;

    etk::EtkEnvMap desc() const;
};

// Replaces non-finite values and negative channels by zero, so they neither light the scene nor
// poison the distribution; returns the number of texels changed.
struct SanitizeReport {
    size_t non_finite = 0, negative = 0;
};
SanitizeReport sanitize_texels(RgbImage& image);

// Reads the map (warning once about texels it had to zero, and about a non-2:1 aspect) and
// builds its distribution.
EnvMap load_envmap(const std::string& path, const DistributionOptions& options);

// Wraps an in-memory image (e.g. the procedural sky) the same way.
EnvMap make_envmap(std::string name, RgbImage image, const DistributionOptions& options);

// Parses "512x256" into a distribution resolution; throws et::Error on anything else.
void parse_resolution(const std::string& text, int& width, int& height);

} // namespace et
