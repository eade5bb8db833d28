// Structured importance sampling (Agarwal, Ramamoorthi, Belongie & Jensen 2003), the baseline of
// the paper's Section 4, and the spherical Voronoi strata it (and `envtrace lights --power
// voronoi`) integrate the map over.
//
// SIS as implemented here, on the map's own texel grid (luminance Y of each texel, solid-angle
// weighted statistics):
//  1. Brightness levels: thresholds t_i = i * sigma(Y), i = 0 .. levels-1; band i holds the texels
//     with t_i <= Y < t_(i+1) (the last band is open above); level i is the nested region Y >= t_i.
//  2. Sample budget: band i has solid angle W_i and power P_i (integral of Y over it); its
//     importance is Gamma_i = P_i * W_i^(1/4) (SIS's metric L^a dw^b with a = 1, b = 1/4, L the
//     region's total illumination: importance sampling's share, tilted towards large regions for
//     the visibility term) and it receives N * Gamma_i / sum Gamma points (largest-remainder
//     rounding, so they add up to N). Reading L as the band's mean radiance instead gives a map
//     like grace.hdr no point at all outside its few bright sources (0 of 32): its whole dim
//     sphere is then lit from the sources' directions and every shadow turns black.
//  3. Placement: from the brightest level down, Hochbaum-Shmoys farthest-point selection inside
//     level i's nested region: the first point of the brightest non-empty level is its brightest
//     texel, every next point the texel of the region whose angular distance to the nearest point
//     placed so far (at any level) is largest.
//  4. Strata: the Voronoi cells of all points on the sphere (each texel goes to its nearest point),
//     with the map's RGB power (sum of texel radiance x texel solid angle) preintegrated per cell.
#pragma once
#include "load/environment_map.h"

#include <glm/glm.hpp>

#include <vector>

namespace et {

// Map-space direction of the centre of texel (row, col).
glm::dvec3 texel_direction(int row, int col, int w, int h);

// The map's integral of L over the sphere, per channel: sum of texel RGB x scale x solid angle.
glm::dvec3 map_power(const EnvMap& env);

// Spherical Voronoi cells of `points` (map space, unit length) over the texels of `env`.
struct VoronoiStrata {
    int width = 0, height = 0;       // texel grid
    std::vector<glm::dvec3> points;  // map space
    std::vector<int> cell;           // per texel: index of the nearest point
    std::vector<double> solid_angle; // per cell
    std::vector<glm::dvec3> power;   // per cell: sum of L x solid angle (RGB, scaled)
    // Sampling tables for jittering inside a cell (kernels/directional_lights.h,
    // etk_dl_stratum_direction): texels sorted by cell, cell k owns texels[begin[k] ..
    // begin[k+1]), cdf the running fraction of the cell's solid angle.
    std::vector<int> texels, begin;
    std::vector<float> cdf;
};
VoronoiStrata voronoi_strata(const EnvMap& env, const std::vector<glm::dvec3>& points,
                             int threads = 0);

struct SisOptions {
    int samples = 64;
    int levels = 6;           // brightness levels (thresholds 0, sigma, ..., (levels-1) sigma)
    double area_power = 0.25; // b in Gamma = L * dw^b
    int threads = 0;          // Voronoi assignment threads (0: all cores)
};

struct SisResult {
    VoronoiStrata strata;
    std::vector<double> thresholds; // luminance
    std::vector<int> level_samples; // points given to each band
    std::vector<int> point_level;   // band that placed each point
    double sigma = 0.0;
    double seconds = 0.0; // whole precomputation (levels, placement, Voronoi)
};

SisResult build_sis(const EnvMap& env, const SisOptions& options);

} // namespace et
