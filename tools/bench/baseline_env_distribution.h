// The distribution builder as it was before the optimisation, for side-by-side comparisons.
#pragma once
#include "env_distribution.h"

namespace et::baseline {

EnvDistribution build_env_distribution(const RgbImage& image, const DistributionOptions& options);
double build_piecewise_constant_1d(const float* f, int n, float* pdf, float* cdf);

} // namespace et::baseline
