// The lat-long parameterisation of directions (y-up, row 0 looks straight up, the image centre
// looks along -Z, u grows towards +X):
//     u = (1 + atan2(x, -z) / pi) / 2,    v = acos(y) / pi
// This is envtrace's own convention, that of ../shared/data/README.md and the ICT probes as
// Probulator reads them. Mitsuba 3's envmap is half a turn about +Y from it and Blender Cycles' a
// quarter turn; the host folds those into the map-to-world rotation (EtkEnvMap's rot_cos,
// rot_sin; host/lib/load/environment_map.h, LatLongConvention), so this stays the one formula.
#ifndef ETK_LATLONG_H
#define ETK_LATLONG_H
#include "compat.h"
#include "trig.h"

ETK_BEGIN

// sin(theta) for theta = pi v, accurate at both poles (sin(pi) in float is not zero): etk_sincospi
// reduces v by the nearest multiple of 1/2 exactly, so near v = 1 it works on v - 1 (0 at the
// pole).
ETK_FN float etk_latlong_sin_theta(float v) {
    return etk_sincospi(v).x;
}

// The direction at longitude coordinate u with the given cos and sin of the colatitude.
ETK_FN float3 etk_latlong_dir(float u, float cos_theta, float sin_theta) {
    float2 phi = etk_sincospi(2.0f * u - 1.0f);
    return make_float3(sin_theta * phi.x, cos_theta, -sin_theta * phi.y);
}

ETK_FN float3 etk_latlong_to_dir(float2 uv) {
    float2 theta = etk_sincospi(uv.y); // the sine is etk_latlong_sin_theta's
    return etk_latlong_dir(uv.x, theta.y, theta.x);
}

// The longitude coordinate u of direction d.
ETK_FN float etk_latlong_u(float3 d) {
    return 0.5f * (1.0f + etk_atan2(d.x, -d.z) * ETK_INV_PI);
}

// theta = atan2(sqrt(x^2 + z^2), y) rather than acos(y): acos loses theta near the poles, where
// y rounds to +-1 for theta below ~3e-4 and a sampled direction would map back to the pole.
ETK_FN float2 etk_dir_to_latlong(float3 d) {
    float u = etk_latlong_u(d);
    float v = etk_atan2(sqrt(d.x * d.x + d.z * d.z), d.y) * ETK_INV_PI;
    return make_float2(u, v);
}

// Density conversion from the unit square to solid angle: |J| = 2 pi^2 sin(theta).
// Zero where sin(theta) is zero: the poles carry no area and are never sampled. The _sin form takes
// the sine a caller has already computed (etk_latlong_sin_theta's, for the direction).
ETK_FN float etk_latlong_pdf_to_solid_angle_sin(float pdf_uv, float sin_theta) {
    return sin_theta > 0.0f ? pdf_uv * ETK_INV_2PI2 / sin_theta : 0.0f;
}
ETK_FN float etk_latlong_pdf_to_solid_angle(float pdf_uv, float v) {
    return etk_latlong_pdf_to_solid_angle_sin(pdf_uv, etk_latlong_sin_theta(v));
}

ETK_END

#endif
