// Environment map -> sampling distribution (paper, Section 3.4), as flat tables ready to upload.
#pragma once
#include "kernels/color.h"
#include "image/image_io.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace et {

// Bounds of the options: a side of at most 65536 cells (etk_find_interval's fixed step count), a
// blur of at most 64 texels (its filter has 2 * ceil(3 sigma) + 3 taps per pass).
constexpr int kMaxDistributionSide = 65536;
constexpr float kMaxBlurSigma = 64.0f;
constexpr float kMinDistributionExponent = 0.05f;

// Entries of the table of a w x h distribution (kernels/piecewise_constant.h), guide tables
// included, in 64 bits.
uint64_t distribution_table_entries(int w, int h);

// Throws et::Error "WxH: problem" when a w x h table is out of range, larger than the device can
// index with 32-bit ints or than the memory budget (util/checked_size.h).
void check_distribution_size(int w, int h);

struct DistributionOptions {
    int width = 0, height = 0; // 0: the map's resolution
    float blur_sigma = 0.5f;   // Gaussian blur of luminance, in texels; 0 disables it
    // The function sampled is luminance^exponent: 1 is the paper's (linear) distribution; below
    // 1 a compressive, tone-mapping-like transform that moves samples from the brightest texels
    // to dimmer ones (the paper's future work; measured in docs/history/results-journal.md).
    float exponent = 1.0f;
    int threads = 0; // rows built on this many threads (0: all cores); same result
};

struct EnvDistribution {
    int width = 0, height = 0; // cells: columns over u (phi), rows over v (theta)
    std::vector<float> table;  // layout of kernels/piecewise_constant.h
    double total = 0.0;        // sum of the sin-weighted function: 0 means no light
    bool has_light() const { return total > 0.0; }
};

// The function sampled for each cell is the exact mean, over the cell, of the bilinearly
// interpolated luminance (a [1 6 1]/8 filter in each direction, so the density is positive
// wherever the radiance lookup is), optionally blurred by a Gaussian of blur_sigma texels,
// area-resampled to the distribution resolution and weighted by sin(theta) at the row centre.
// Texels must already be finite and non-negative (see envmap.h).
EnvDistribution build_env_distribution(const RgbImage& image, const DistributionOptions& options);

// build_env_distribution in pieces, for a map whose rows are still arriving: load_envmap builds
// blocks of rows as soon as the rows they read are decoded. A block is a band of distribution
// rows; its result does not depend on which thread builds it or when, so the table is the same
// for any number of threads.
class DistributionBuilder {
  public:
    // Plans the distribution of a width x height map and allocates its table (zeroed); throws
    // et::Error when the resolution is out of range (check_distribution_size).
    DistributionBuilder(int width, int height, const DistributionOptions& options);
    ~DistributionBuilder();
    DistributionBuilder(const DistributionBuilder&) = delete;
    DistributionBuilder& operator=(const DistributionBuilder&) = delete;

    int blocks() const;
    // Block b reads map rows [0, rows_needed(b)): they must be final before build_block(b).
    int rows_needed(int block) const;
    // Builds one block from the map's texels (width x height x RGB, row-major, of which rows
    // [0, rows_needed(block)) are read). Distinct blocks may be built concurrently.
    void build_block(const float* rgb, int block);
    // The marginal distribution, once every block is built; leaves the builder empty.
    EnvDistribution finish();

  private:
    struct State;
    std::unique_ptr<State> s_;
};

// Rec. 709 luminance of an RGB texel (kernels/color.h).
inline float luminance(const float* rgb) {
    return etk::etk_luma(etk::make_float3(rgb[0], rgb[1], rgb[2]));
}

// The least share of a float CDF (0 ... 1) an interval with mass keeps: 2^-21, eight float
// steps just below 1. A float CDF cannot hold widths near 1e-8 of the whole where it nears 1:
// under a sun 1e10 x its sky the rows after the sun's had no width, and the kernels (which
// sample and evaluate densities from the widths) never drew that sky. Intervals below the share
// are raised to it (the maps of ../shared/data have up to 3 such rows and 76 such texels, near
// black or at a pole: their densities rise to the share, a shift below 1e-4 of the table).
constexpr double kMinCdfShare = 0x1p-21;
// A CDF interval's weight v as the CDF holds it, `least` = kMinCdfShare x the weights' sum.
inline double raised_to_least_share(double v, double least) {
    return v > 0.0 ? (v > least ? v : least) : 0.0;
}

// The 1D building block: density and CDF (n+1 entries) of f, as in the paper's Figure 2, every
// interval with mass at least kMinCdfShare of the CDF (the densities stay f's own). Returns the
// sum of f.
double build_piecewise_constant_1d(const float* f, int n, float* pdf, float* cdf);

// The guide table (cutpoint method) of a CDF of n intervals: etk_guide_cells(n) + 1 entries,
// entry k the interval etk_find_interval returns for u = k / K, the last n - 1. One pass over
// the CDF. Every 2D table's builder calls it for the marginal and each conditional CDF.
void build_cdf_guide(const float* cdf, int n, float* guide);

} // namespace et
