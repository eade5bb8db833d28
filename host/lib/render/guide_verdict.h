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
// sample); otherwise the passes that follow render the fallback, with its batched map samples.
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
// A third technique (an alternative to the fallback, VisibilityOptions::alternative) may be
// measured as the fallback is, on the same pixels: each technique's error times its time per
// sample (relative to the fallback's) is then its cost per error, and the tables stay where theirs
// is at most the cheaper fallback's; otherwise the cheaper of the two renders the rest.
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
    // alternative_cost > 0: a third technique, measured (t = 2) at that time per sample.
    GuideVerdict(int width, int height, int passes, double cost, double alternative_cost = 0.0);
    // Adds the film of pass k (0 .. passes - 1, in order) of technique t (0: the fallback, 1:
    // the tables, 2: the alternative): film_sum per pixel, RGB and w the samples it holds.
    void add(int t, int k, const float* film_sum_rgba);
    // After the last pass: the verdict and the errors it compared.
    bool tables_win() const;
    bool alternative_wins() const; // the alternative rather than the fallback, where not tables
    double fallback_error() const { return error_[0]; }
    double tables_error() const { return error_[1]; }
    double alternative_error() const { return error_[2]; }

  private:
    void decide();
    // The cheaper fallback's cost per error: the fallback's error, or the alternative's times
    // its cost where that is less.
    double fallback_score() const;
    size_t pixels_;
    int width_, passes_, techniques_, added_[3] = {0, 0, 0};
    double cost_, alternative_cost_;
    // Per technique t and block b (index 2 t + b), per pixel: the block's luminance sum, samples.
    std::vector<double> sum_[6];
    std::vector<uint32_t> n_[6];
    double error_[3] = {0.0, 0.0, 0.0};
    bool decided_ = false;
};

} // namespace et
