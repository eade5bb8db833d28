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

// The lat-long convention a map was made for: which direction each texel means. envtrace's own is
// that of kernels/latlong.h (the image centre looks along -Z, u grows towards +X, row 0 looks
// up). With a y-up world, Mitsuba 3's envmap (u = atan2(x, -z) / 2 pi mod 1, v = acos(y) / pi)
// is the same map turned half a turn about +Y, and Blender Cycles' (direction_to_equirectangular
// in Blender's z-up world, brought to y-up by (x, y, z)_blender -> (x, z, -y)) a quarter turn:
//     u_mitsuba = u - 1/2,   u_blender = u - 1/4 (mod 1),   v the same in all three.
// Neither is mirrored, so a convention is a fixed rotation about +Y, folded into the map-to-world
// rotation of desc(): the kernels keep one formula and radiance, sampling and pdf turn together.
enum class LatLongConvention : int { envtrace, mitsuba, blender };

// The rotation, in the sense of EnvMap::rotation_degrees, that turns envtrace's convention into
// `c`: 0, 180 and 90 degrees.
double convention_rotation_degrees(LatLongConvention c);
const char* name_of(LatLongConvention c);
// "envtrace", "mitsuba" or "blender"; false for anything else.
bool parse_convention(const std::string& name, LatLongConvention& out);

struct EnvMap {
    std::string name;
    RgbImage image;
    EnvDistribution dist;
    float scale = 1.0f;
    // About the up (+Y) axis. Positive turns the map clockwise seen from above (from +Y): what
    // the map shows towards -Z moves towards +X, i.e. a right-handed rotation by -rotation_degrees
    // about +Y. The texel at u lands where the unturned map has u + rotation_degrees / 360.
    float rotation_degrees = 0.0f;
    LatLongConvention convention = LatLongConvention::envtrace; // applied before the rotation
    float max_texel = 0.0f; // the largest channel value of `image`
    // load_envmap: seconds until the texels were decoded and sanitised, and the distribution's
    // thread time over the threads that built it (it overlaps the decoding).
    double load_seconds = 0.0, build_seconds = 0.0;

    // The kernels' descriptor: map-to-world rotation by rotation_degrees plus the convention's.
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

// Exact solid angle of texel row `row` of an h-row lat-long grid, per texel of a w-wide row.
double texel_solid_angle(int row, int w, int h);

// Wraps an in-memory image (e.g. the procedural sky) the same way.
EnvMap make_envmap(std::string name, RgbImage image, const DistributionOptions& options);

// Clamps env.scale so that scale x max_texel <= kMaxRadiance, warning (naming `where`) if it had
// to.
void bound_intensity(EnvMap& env, const std::string& where);

// Parses "512x256" into a distribution resolution; throws et::Error on anything else.
void parse_resolution(const std::string& text, int& width, int& height);

} // namespace et
