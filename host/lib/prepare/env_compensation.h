// MIS compensation of the map's distribution (Karlik, Sik, Vevoda, Skrivan, Krivanek 2019).
// Where a light sample is combined by MIS with a BSDF sample that can reach every direction, the
// light technique need not cover the dim part of the sphere: the BSDF covers it, and the MIS
// weights sum to one wherever either density is positive. Sampling max(0, L - mean L) instead of
// L moves the light samples onto the bright sources, where they beat the BSDF, and leaves the
// diffuse remainder to the BSDF sample, which handles smooth light well.
//
// Why the mean: it is Karlik et al.'s choice and pbrt-v4's (ImageInfiniteLight's
// compensatedDistribution). A constant map then has no compensated mass at all (the BSDF is the
// right technique for it), and a map with one small bright source keeps almost all of it.
#pragma once
#include "load/env_distribution.h"

namespace et {

// The compensated twin of `full` (same resolution and layout): per cell, max(0, f - mean f) sin
// theta, where f is the cell's function value (its density over sin theta at the row centre) and
// the mean is over solid angle. When nothing is above the mean (a constant map) the result is a
// copy of `full`, so that the strategy stays a plain MIS there rather than losing its light
// technique.
EnvDistribution compensate_distribution(const EnvDistribution& full);

} // namespace et
