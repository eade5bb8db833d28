// The cosine strategy's light tables (kernels/normal_bins.h): for every bin of normals, a
// distribution over the map's ETK_GUIDE_REGIONS regions (kernels/visibility_guide.h layout, one
// slot per bin) proportional to an upper bound of the map's light in each region times the clamped
// cosine to any normal of the bin (cosine_bin_weights), mixed with the map's own region masses for
// a defensive share alpha. Sampled as the visibility strategy's cells are: a region from the bin's
// table, then the map inside it, so the density is the map's times Q(R) / M_R, positive wherever
// the map is.
#pragma once
#include "kernels/envmap.h"

#include <vector>

namespace et {

// Per bin, per region (ETK_NORMAL_BINS x ETK_GUIDE_REGIONS): the region's weight, an upper bound
// of the map's light in it times max(0, n . w) for every normal n of the bin (the map's
// distribution's mass per texel, so 1 is the whole map's). The tables' proportions.
std::vector<double> cosine_bin_weights(const std::vector<float>& dist, const etk::EtkEnvMap& env);

// Every bin's table, ETK_GUIDE_CELL_FLOATS floats a bin (its CDF over the regions, then a light
// count of 1), from the map's distribution (dist, dist_w x dist_h: piecewise_constant.h layout),
// its region tables (guide_region_tables) and its map-to-world rotation (env).
std::vector<float> cosine_bin_tables(const std::vector<float>& dist,
                                     const std::vector<float>& regions, const etk::EtkEnvMap& env,
                                     float alpha);

} // namespace et
