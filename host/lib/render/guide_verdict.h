// The visibility strategy's verdict: whether its learned tables pay for what they cost.
//
// The tables cost time at every vertex (the cell's hash, the guided sample and its densities,
// the continuation guide: 1.19-1.61x MIS's time per sample after learning, 2-2.3x while learning
// on the efficiency suite; docs/history/results-journal.md) and save much variance only where the
// map's light is blocked in ways the map's own distribution cannot see -- rooms lit through
// openings, not a row of spheres under the open sky (the efficiency suite: 0.58-1.21x MIS's
// efficiency at equal spp x time, 0.77x in geometric mean).
//
// Which of the two a scene is, is measured, not modelled: `passes` passes of the tables after
// some learning (VisibilityOptions::verdict_after; part of the image, as any) and as many passes
// of the fallback (the paper's MIS, or compensated for auto), rendered only to measure (sample
// indices of their own, renderer.h; for auto on every 8th pixel only, VisibilityOptions::
// verdict_stride, and the two compared there), each in two blocks of passes / 2 consecutive
// samples. Per pixel and technique, half the squared difference of its two blocks' means estimates
// the error of a block-sized estimate, relative to the squared mean of the pixel's 5 x 5
// neighbourhood (plus 1% of the image's mean, so black pixels do not divide by zero, as
// tools/experiments' relative MSE); the mean over the image of each technique's value, every
// pixel's capped at the 99.9% quantile (a firefly in one block must not decide), is its error. The
// tables stay when the fallback's error is at least `cost` times theirs (the time they cost per
// sample) by one standard error of the ratio's log, from the pixels' spread (log_ratio_se: a ratio
// that a few pixels make is not yet a measurement); otherwise the passes that follow render the
// fallback, with its batched map samples.
// The fallback's passes are not kept: in a room lit through a window, 8 of them among 300 passes
// of the tables would add 20% to the image's variance.
//
// Blocks of consecutive samples, not the samples' variance: the Sobol' points stratify each
// block, and the map's smooth warp keeps more of that stratification than the learned tables'
// piecewise one (the efficiency suite, 128 spp: the per-sample variance favoured the tables up to
// 1.7x where the two-seed variance of the images favoured MIS -- as the adaptive strategy found,
// docs/history/results-journal.md). Comparing the same pixels rendered both ways measures the
// estimators on this image: a model of the second moments (the learned shares' way) leaves out the
// MIS weights, the stratification and the continuation's indirect light. The larger the blocks,
// the more of the stratification they see: blocks of 2 overstated the tables under the open sky
// by 1.2-1.7x, blocks of 8 did not (auto_visibility_options).
//
// The kept passes' technique is the tables' in the verdict's first use; where the screen
// dropped the tables at depth 1 (render/visibility_learning.h) it is the binned light samples
// instead, weighed against the fallback as the tables are, at their own cost.
//
// The verdict depends on the passes' film values alone: the seed's, on every thread count and
// wave size, and on a process that starts past them (it renders them first, renderer.cpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace et {

class GuideVerdict {
  public:
    // cost: the kept technique's time per sample over the fallback's.
    GuideVerdict(int width, int height, int passes, double cost);
    // Adds the film of pass k (0 .. passes - 1, in order) of technique t (0: the fallback, 1:
    // the kept passes' technique): film_sum per pixel, RGB and w the samples it holds.
    void add(int t, int k, const float* film_sum_rgba);
    // After the last pass: the verdict and the errors it compared. kept_wins: the kept passes'
    // technique renders on.
    bool kept_wins() const;
    double fallback_error() const { return error_[0]; }
    double kept_error() const { return error_[1]; }
    // The standard error of log(fallback_error / kept_error), from the spread of the pixels'
    // values (the delta method for a ratio of means); 0 where nothing was compared.
    double log_ratio_se() const { return log_ratio_se_; }

  private:
    void decide();
    size_t pixels_;
    int width_, passes_, added_[2] = {0, 0};
    double cost_;
    // Per technique t and block b (index 2 t + b), per pixel: the block's luminance sum, samples.
    std::vector<double> sum_[4];
    std::vector<uint32_t> n_[4];
    double error_[2] = {0.0, 0.0};
    double log_ratio_se_ = 0.0;
    bool decided_ = false;
};

} // namespace et
