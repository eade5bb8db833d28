// The estimated relative error of a render's image, from the film's exact sums, for
// `render --noise-target X`: the render stops once it is at most X.
//
// Per pixel with n >= 2 samples, the variance of the mean of each channel is estimated from the
// sums of the samples and of their squares, v_c = s_c^2 / n (FilmSums::variance_of_mean), and
// the pixel's relative variance is r = (v_R + v_G + v_B) / (m_R^2 + m_G^2 + m_B^2 + eps^2): the
// squared relative standard error of the pixel's RGB vector. eps = 0.01 x the image's RMS pixel
// value (sqrt of the mean over pixels of m_R^2 + m_G^2 + m_B^2), so that pixels far darker than
// the image do not need a relative precision that no one can see. The image's relative error is
// the root mean square over the pixels, E = sqrt(mean of r): the relative RMS error of the
// image, which is what `envtrace compare` reports against a reference (its relative L2 error).
//
// Samples within a pixel come from one randomized Sobol' sequence, so they are not independent:
// s^2/n is the variance of the mean of n independent samples, and the randomized QMC estimate
// usually has less (stratification), so E is usually conservative (docs/outputs.md, "Noise
// target", with measurements).
#pragma once
#include "render/film_sums.h"

#include <cstdint>

namespace et {

// E as above; +inf while any pixel has fewer than 2 samples.
double relative_error(const FilmSums& sums);

// The first check of a noise target: fewer samples make the variance estimate itself too noisy.
constexpr int64_t kNoiseFirstCheck = 16;

// The sample count at which to check again, after E = `error` at `spp` samples against the
// target: where E would meet the target if it falls as 1/sqrt(n), at least spp + 1 and at most
// 2 spp (so a bad early estimate costs at most one doubling).
int64_t next_noise_check(int64_t spp, double error, double target);

} // namespace et
